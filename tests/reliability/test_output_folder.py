"""The output folder (docs/user-guide/reliability.md, "Output folder"): a run never
replaces another run's output unless asked (-thm_overwrite), and then only
the files of that run's manifest; a folder in use is locked; a run refused
for its input leaves the folder as it found it."""
import fcntl
import os
import signal
import subprocess
import sys
import time

from petsc4py import PETSc

from conftest import LAUWERIER_COARSE, MPI_ENV, ROOT, folder_digests, read_json, read_text, run_petthm

ERFC = ("heat_erfc", "-thm_final_time", 1e3)
LAUWERIER = (*LAUWERIER_COARSE, "-thm_final_time", 1e6)


def _one_error_line(proc):
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("petthm: error: "), proc.stderr
    return lines[0]


def test_a_finished_run_is_refused_then_replaced_with_overwrite_keeping_the_users_files(tmp_path):
    """A run into the folder of a finished run stops (exit 2) naming
    -thm_restart and -thm_overwrite and changes nothing; with -thm_overwrite
    another scene replaces it: the old run's files are gone (no stale
    fracture.* beside the new fields), the user's files in the folder stay."""
    out = tmp_path / "run"
    run_petthm(LAUWERIER[0], out, *LAUWERIER[1:])
    for name, text in (("my.opts", "-thm_rock_conductivity 3\n"), ("job.log", "log\n"),
                       ("mine.msh", "$MeshFormat\n")):
        (out / name).write_text(text)
    before = folder_digests(out)
    proc, _ = run_petthm(ERFC[0], out, *ERFC[1:], check=False)
    msg = _one_error_line(proc)
    assert proc.returncode == 2 and "-thm_restart" in msg and "-thm_overwrite" in msg, msg
    assert folder_digests(out) == before
    proc, summary = run_petthm(ERFC[0], out, *ERFC[1:], "-thm_overwrite")
    assert summary["scene"] == "heat_erfc" and summary["status"] == "completed"
    names = set(os.listdir(out))
    assert {"my.opts", "job.log", "mine.msh"} <= names
    assert not any(n.startswith("fracture") for n in names), names
    assert read_json(out / "manifest.json")["files"]


def test_the_default_folder_follows_the_same_rules(tmp_path):
    """output/SCENE of the working folder: the second run is refused."""
    cmd = [sys.executable, "-m", "petthm", ERFC[0], *map(str, ERFC[1:]), "-thm_quiet"]
    env = dict(os.environ, **MPI_ENV)
    first = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    second = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert first.returncode == 0, first.stderr
    assert second.returncode == 2 and "output/heat_erfc" in _one_error_line(second)


def test_a_folder_of_an_earlier_petthm_without_manifest_is_recognised(tmp_path):
    out = tmp_path / "old"
    run_petthm(*ERFC[:1], out, *ERFC[1:])
    os.remove(out / "manifest.json")
    proc, _ = run_petthm(*ERFC[:1], out, *ERFC[1:], check=False)
    assert proc.returncode == 2 and "holds the output of another run" in _one_error_line(proc)
    (out / "keep.txt").write_text("mine")
    run_petthm(*ERFC[:1], out, *ERFC[1:], "-thm_overwrite")
    assert (out / "keep.txt").read_text() == "mine"


def test_a_locked_folder_is_refused_naming_the_holder(tmp_path):
    """The lock of a running run (here held by the test, as host:pid) stops a
    second run at once with the holder's name; released, the folder is free."""
    out = tmp_path / "locked"
    out.mkdir()
    with open(out / ".petthm.lock", "w") as f:
        f.write("otherhost:4242\n")
        f.flush()
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        proc, _ = run_petthm(*ERFC[:1], out, *ERFC[1:], check=False)
    msg = _one_error_line(proc)
    assert proc.returncode == 2 and "in use by the run otherhost:4242" in msg, msg
    assert not (out / "history.csv").exists()
    run_petthm(*ERFC[:1], out, *ERFC[1:])


def test_two_runs_into_one_folder_the_second_stops_and_the_first_keeps_its_history(tmp_path):
    """Run A is running; run B (another conductivity) into its folder stops
    at once naming A's process; A completes with only its own rows."""
    out = tmp_path / "shared"
    cmd = [sys.executable, "-m", "petthm", *map(str, LAUWERIER), "-thm_output_dir", str(out), "-thm_quiet",
           "-thm_final_time", 1e8]
    a = subprocess.Popen(list(map(str, cmd)), cwd=ROOT, env=dict(os.environ, **MPI_ENV),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    end = time.time() + 120
    while not (out / "history.csv").exists() and time.time() < end:
        time.sleep(0.02)
    proc, _ = run_petthm(*LAUWERIER[:1], out, *LAUWERIER[1:], "-thm_rock_conductivity", 5, check=False)
    a.communicate(timeout=300)
    msg = _one_error_line(proc)
    assert proc.returncode == 2 and f":{a.pid}" in msg, msg
    assert a.returncode == 0
    summary = read_json(out / "summary.json")
    assert summary["provenance"]["parameters"]["-thm_rock_conductivity"] == 2.88
    times = [line.split(",")[1] for line in read_text(out / "history.csv").splitlines()[1:]]
    assert len(times) == len(set(times)) == summary["steps"] + 1


def test_a_killed_run_leaves_no_stale_lock(tmp_path):
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "petthm", *map(str, LAUWERIER), "-thm_output_dir", str(out), "-thm_quiet",
           "-thm_final_time", 1e8]
    a = subprocess.Popen(list(map(str, cmd)), cwd=ROOT, env=dict(os.environ, **MPI_ENV),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    end = time.time() + 120
    while not (out / "history.csv").exists() and time.time() < end:
        time.sleep(0.02)
    a.send_signal(signal.SIGKILL)
    a.wait(timeout=60)
    proc, summary = run_petthm(*ERFC[:1], out, *ERFC[1:], "-thm_overwrite")
    assert summary["status"] == "completed"


def test_a_file_system_without_locks_is_named_once_and_the_run_goes_on(tmp_path, monkeypatch):
    from petthm.io.rundir import RunFolder

    def no_locks(f, how):
        raise OSError(37, "No locks available")
    monkeypatch.setattr(fcntl, "flock", no_locks)
    folder = RunFolder(str(tmp_path / "nfs"), PETSc.COMM_SELF)
    folder.open(continuing=False, overwrite=False)
    assert len(folder.notes) == 1 and "has no locks" in folder.notes[0]
    assert (tmp_path / "nfs" / "manifest.json").exists()


def test_a_run_refused_after_it_started_writing_leaves_the_folder_as_it_found_it(tmp_path):
    """An input error found after the first step (a misspelt PETSc option)
    removes this run's files (and only these): the corrected command then
    runs in the same folder without -thm_overwrite."""
    out = tmp_path / "typo"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    proc, _ = run_petthm(*ERFC[:1], out, *ERFC[1:], "-ksp_tpye", "cg", check=False)
    assert proc.returncode == 2 and "-ksp_tpye" in _one_error_line(proc)
    assert sorted(n for n in os.listdir(out) if not n.startswith(".")) == ["manifest.json", "notes.txt"]
    run_petthm(*ERFC[:1], out, *ERFC[1:])
