"""Checkpoint and restart (issue 15): a run killed (kill -9) or stopped by
a signal continues with -thm_restart to the uninterrupted run's final
state, on the same or another rank count (values are keyed by the serial
mesh's points, not by the partition)."""
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from conftest import (
    MPI_ENV,
    ROOT,
    checkpoint_state,
    ranks_of,
    read_csv,
    read_json,
    read_text,
    run_petthm,
    solver_without_parallel_direct,
)
from petthm.io.output import read_output

#: a coarse lauwerier (128 steps in ~2 s): what is tested is the restart, not the resolution
LAUWERIER = ("lauwerier", ("-thm_mesh_size", 20, "-thm_lauwerier_fracture_size", 5, "-thm_final_time", 1e6))
SCENE2 = ("penny_impermeable", ("-options_file", f"{ROOT}/options/scenes/penny_impermeable.opts",
                                "-thm_scene2_fracture_size", 40, "-thm_scene2_well_size", 20,
                                "-thm_scene2_layer", 0, "-thm_final_time", 1e7))


def _start(scene, outdir, options, ranks=1):
    cmd = [sys.executable, "-m", "petthm", scene, "-thm_output_dir", str(outdir), "-thm_quiet",
           *map(str, options)]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    return subprocess.Popen(cmd, cwd=ROOT, env=dict(os.environ, **MPI_ENV), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _wait_for(path, rows=0, timeout=300):
    """Until ``path`` exists (and, for a CSV, has more than ``rows`` rows)."""
    end = time.time() + timeout
    while time.time() < end:
        if os.path.exists(path) and (not rows or len(read_text(path).splitlines()) > rows + 1):
            return
        time.sleep(0.05)
    raise AssertionError(f"{path} did not appear")


def _final_state(outdir):
    """The checkpoint's values in the order of the serial mesh's points (any rank count)."""
    return checkpoint_state(outdir)


def _final_output(outdir, name="Tm"):
    """The last output of ``fields.h5`` (read on its own mesh), nodes sorted by coordinates."""
    xyz, _, _, fields = read_output(str(outdir / "fields.h5"))
    order = np.lexsort(np.round(xyz, 9).T[::-1])
    return xyz[order], fields[name][order]


def _times(outdir):
    return [float(r["time"]) for r in read_csv(os.path.join(outdir, "history.csv"))]


@pytest.mark.parametrize("scene,options,every", [
    (*LAUWERIER, ("-thm_checkpoint_interval", 5)),
    pytest.param(*SCENE2, ("-thm_checkpoint_interval", 5), marks=pytest.mark.first_pass_only),
    (*LAUWERIER, ("-thm_checkpoint_interval", 0, "-thm_checkpoint_wall", 1e-9)),
    (SCENE2[0], ("-thm_thermomechanical_heating", "true", *SCENE2[1]), ("-thm_checkpoint_interval", 5))],
    ids=["lauwerier", "scene2", "lauwerier-wall", "scene2-heating"])
def test_kill_9_then_restart_gives_the_uninterrupted_run(tmp_path, scene, options, every):
    """A fracture TH scene and a contact scene (Scene 2: u, lam, pf, Tf,
    Tm), killed with SIGKILL after their first checkpoint (every 5 steps,
    or by wall time: -thm_checkpoint_wall): -thm_restart continues to the
    uninterrupted run's final state (1e-10) and history (the rows after the
    checkpoint are written again, once)."""
    _, ref = run_petthm(scene, tmp_path / "ref", *options)
    out = tmp_path / "killed"
    proc = _start(scene, out, (*options, *every))
    _wait_for(out / "checkpoint.h5")
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=60)
    with h5py.File(out / "checkpoint.h5", "r") as h5:       # killed mid-run, not after the end
        assert h5.attrs["time"] < float(options[-1])
    _, s = run_petthm(scene, out, "-thm_restart", out, *options)
    x_ref, meta_ref = _final_state(tmp_path / "ref")
    x, meta = _final_state(out)
    print(scene, "relative difference", np.abs(x - x_ref).max() / np.abs(x_ref).max())
    assert s["status"] == "completed" and meta["time"] == meta_ref["time"]
    assert np.abs(x - x_ref).max() <= 1e-10 * np.abs(x_ref).max()
    assert _times(out) == _times(tmp_path / "ref")
    rows, rows_ref = (read_csv(d / "history.csv") for d in (out, tmp_path / "ref"))
    if "heating_allowance" in rows_ref[0]:               # the heating's allowance goes on as it was
        a, a_ref = (np.array([float(r["heating_allowance"]) for r in rr]) for rr in (rows, rows_ref))
        assert a_ref[-1] > 0.0 and np.abs(a - a_ref).max() <= 1e-8 * a_ref[-1]


@pytest.mark.parametrize("scene,options",
                         [LAUWERIER, pytest.param(*SCENE2, marks=pytest.mark.first_pass_only)],
                         ids=["lauwerier", "scene2"])
def test_kill_9_on_two_ranks_then_restart_gives_the_uninterrupted_run(tmp_path, scene, options):
    """2 ranks, each killed with SIGKILL after the first checkpoint (a node
    lost): -thm_restart on 2 ranks reaches the uninterrupted 2-rank run's
    final state (1e-10: the partitions may differ from run to run)."""
    if scene == SCENE2[0]:                    # contact: the block recipe where there is no MUMPS
        options = (*options, *solver_without_parallel_direct())
    run_petthm(scene, tmp_path / "ref", *options, ranks=2)
    out = tmp_path / "killed"
    proc = _start(scene, out, (*options, "-thm_checkpoint_interval", 5), ranks=2)
    _wait_for(out / "checkpoint.h5")
    ranks = ranks_of(proc.pid)
    for pid in ranks:
        os.kill(pid, signal.SIGKILL)
    proc.communicate(timeout=60)
    with h5py.File(out / "checkpoint.h5", "r") as h5:
        assert h5.attrs["time"] < float(options[options.index("-thm_final_time") + 1])
    _, s = run_petthm(scene, out, "-thm_restart", out, *options, ranks=2)
    x_ref, _ = _final_state(tmp_path / "ref")
    x, _ = _final_state(out)
    rel = np.abs(x - x_ref).max() / np.abs(x_ref).max()
    print(scene, len(ranks), "ranks killed; relative difference", rel)
    assert s["status"] == "completed" and len(ranks) >= 2
    assert np.abs(x - x_ref).max() <= 1e-10 * np.abs(x_ref).max()
    assert _times(out) == _times(tmp_path / "ref")


def test_signal_checkpoints_and_stops_then_restart_on_two_ranks_or_one(tmp_path):
    """2 ranks: a signal stops the run after its step with a checkpoint,
    status interrupted and exit code 3 (SIGUSR1: Open MPI's mpiexec
    forwards it to the ranks, where SIGTERM makes it kill the job; under
    srun SIGTERM reaches the ranks themselves).  The restart on 2 ranks, and
    one on 1 rank from a copy of the folder, reach the uninterrupted 2-rank
    run's final state (1e-10: the partitions differ from run to run)."""
    import shutil
    scene, options = LAUWERIER
    run_petthm(scene, tmp_path / "ref", *options, ranks=2)
    out = tmp_path / "stopped"
    proc = _start(scene, out, (*options, "-thm_checkpoint_interval", 0), ranks=2)
    _wait_for(out / "history.csv", rows=5)
    proc.send_signal(signal.SIGUSR1)
    stdout, stderr = proc.communicate(timeout=120)
    s = read_json(out / "summary.json")
    assert proc.returncode == 3, stdout + stderr
    assert s["status"] == "interrupted" and "SIGUSR1" in s["message"] and "Traceback" not in stderr
    assert os.path.exists(out / "checkpoint.h5") and s["final_time"] < 1e6
    shutil.copytree(out, tmp_path / "serial")
    x_ref, _ = _final_state(tmp_path / "ref")
    field_ref = _final_output(tmp_path / "ref")
    for folder, ranks in ((out, 2), (tmp_path / "serial", 1)):
        _, s = run_petthm(scene, folder, "-thm_restart", folder, *options, ranks=ranks)
        x, _ = _final_state(folder)
        print(ranks, "rank(s): relative difference", np.abs(x - x_ref).max() / np.abs(x_ref).max())
        assert s["status"] == "completed"
        assert np.abs(x - x_ref).max() <= 1e-10 * np.abs(x_ref).max()
        field = _final_output(folder)              # the output series goes on, on the restart's mesh
        assert np.array_equal(field[0], field_ref[0])
        assert np.abs(field[1] - field_ref[1]).max() <= 1e-10 * np.abs(field_ref[1]).max()
    with h5py.File(tmp_path / "serial" / "fields.h5", "r") as h5:
        meshes = list(h5.attrs["meshes"])      # 1 rank numbers the nodes unlike 2: a new mesh group
        assert meshes[0] == "mesh" and meshes[-1] == "mesh_1" and "mesh_1/geometry" in h5


def test_sigterm_stops_a_serial_run(tmp_path):
    """SIGTERM on one rank: interrupted, exit code 3, a checkpoint."""
    scene, options = LAUWERIER
    out = tmp_path / "stopped"
    proc = _start(scene, out, options)
    _wait_for(out / "history.csv", rows=3)
    proc.send_signal(signal.SIGTERM)
    proc.communicate(timeout=120)
    s = read_json(out / "summary.json")
    assert proc.returncode == 3 and s["status"] == "interrupted" and "SIGTERM" in s["message"]
    assert os.path.exists(out / "checkpoint.h5")


def test_restart_errors_are_one_line(tmp_path):
    """No checkpoint in the folder, or another scene's checkpoint."""
    proc, _ = run_petthm("lauwerier", tmp_path, "-thm_restart", tmp_path, check=False)
    assert proc.returncode == 2 and "no checkpoint.h5" in proc.stderr
    run_petthm("heat_erfc", tmp_path / "heat", "-thm_final_time", 1e3)
    proc, _ = run_petthm("lauwerier", tmp_path / "heat", "-thm_restart", tmp_path / "heat", check=False)
    assert proc.returncode == 2 and "scene heat_erfc" in proc.stderr


def test_a_restart_alone_goes_on_in_its_folder(tmp_path):
    """``-thm_restart DIR`` without ``-thm_output_dir`` (as the error for two
    folders asks): the run ends in DIR with every file a scene writes at its
    end there (Scene 2's fracture maps went to output/<scene> of the working
    folder, and the run ended in a traceback where that folder was missing)."""
    scene, options = SCENE2
    first = (*options[:-1], 3e6)
    out = tmp_path / "run"
    run_petthm(scene, out, *first)
    os.remove(out / "fracture_final.npz")
    cmd = [sys.executable, "-m", "petthm", scene, "-thm_restart", str(out), "-thm_quiet", *map(str, options)]
    proc = subprocess.run(cmd, cwd=tmp_path, env=dict(os.environ, **MPI_ENV), capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    summary = read_json(out / "summary.json")
    assert summary["status"] == "completed" and summary["final_time"] == float(options[-1])
    assert (out / "fracture_final.npz").exists() and not (tmp_path / "output").exists()
