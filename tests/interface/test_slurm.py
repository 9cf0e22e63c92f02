"""The SLURM job scripts (issue 15): a job stopped by SLURM's signal before
its time limit submits its continuation (afterany on itself, with
PETTHM_CONTINUE=1), which restarts from the checkpoint and completes.  srun
and sbatch are stand-ins on PATH: srun runs the command (and, when asked,
sends it SIGTERM once history.csv has rows, as SLURM's --signal does);
sbatch writes its arguments to a file."""
import os
import shlex
import stat
import subprocess
import sys

import pytest

from conftest import MPI_ENV, ROOT, read_csv, read_json, read_text

#: shell stand-ins for SLURM, no PETSc: the same on every PETSc version
pytestmark = pytest.mark.first_pass_only

SRUN = """#!/bin/bash
"$@" &
pid=$!
if [ -n "${FAKE_SIGNAL_AFTER_ROWS:-}" ]; then
    until [ -f "$PETTHM_OUT/history.csv" ] && \\
          [ "$(wc -l < "$PETTHM_OUT/history.csv")" -gt "$FAKE_SIGNAL_AFTER_ROWS" ]; do sleep 0.05; done
    kill -TERM "$pid"
fi
wait "$pid"
"""
SBATCH = """#!/bin/bash
printf '%s\\n' "$*" >> "$FAKE_SBATCH_LOG"
"""


def _tool(folder, name, text):
    path = folder / name
    path.write_text(text)
    path.chmod(path.stat().st_mode | stat.S_IEXEC)


@pytest.fixture
def slurm(tmp_path):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    _tool(bin_dir, "srun", SRUN)
    _tool(bin_dir, "sbatch", SBATCH)
    env = dict(os.environ, **MPI_ENV, PATH=f"{bin_dir}:{os.environ['PATH']}", SLURM_SUBMIT_DIR=str(ROOT),
               SLURM_JOB_ID="4242", PETTHM_PYTHON=sys.executable, PETTHM_OUT=str(tmp_path / "out"),
               FAKE_SBATCH_LOG=str(tmp_path / "sbatch.log"))

    def job(script, *args, **more):
        return subprocess.run(["bash", f"slurm/{script}", *map(str, args)], cwd=ROOT, text=True,
                              capture_output=True, env=dict(env, **more), timeout=600)
    return job


def test_a_job_stopped_before_its_time_limit_chains_its_restart(slurm, tmp_path):
    args = ("lauwerier", "options/scenes/lauwerier.opts", "-thm_final_time", "1e6", "-thm_quiet")
    first = slurm("run_scene.sbatch", *args, FAKE_SIGNAL_AFTER_ROWS="4")
    out = tmp_path / "out"
    summary = read_json(out / "summary.json")
    assert first.returncode == 3 and summary["status"] == "interrupted", first.stdout + first.stderr
    assert (out / "checkpoint.h5").exists() and list(out.glob("log_view-4242.txt"))
    submitted = shlex.split(read_text(tmp_path / "sbatch.log"))
    assert submitted[0] == "--dependency=afterany:4242"
    assert submitted[1].startswith("--export=ALL,PETTHM_CONTINUE=1,PETTHM_OUT=")
    assert submitted[2:] == ["slurm/run_scene.sbatch", *args]
    second = slurm("run_scene.sbatch", *args, PETTHM_CONTINUE="1")    # the chained job
    summary = read_json(out / "summary.json")
    assert second.returncode == 0 and summary["status"] == "completed", second.stdout + second.stderr
    times = [float(r["time"]) for r in read_csv(out / "history.csv")]
    assert times[-1] == pytest.approx(1e6) and len(times) == len(set(times))
    assert len(read_text(tmp_path / "sbatch.log").splitlines()) == 1    # a completed run ends the chain


def test_scene_scripts_name_their_scene_and_resubmit_themselves():
    """Each paper scene's script asks for ranks, a time limit and the
    signal, and resubmits itself (not the generic script)."""
    for script, scene in (("scene1", "rigid_fracture"), ("scene2", "penny_impermeable"),
                          ("scene3", "inclined_penny")):
        text = read_text(os.path.join(ROOT, "slurm", f"{script}.sbatch"))
        for directive in ("--ntasks=", "--time=", "--signal=TERM@"):
            assert f"#SBATCH {directive}" in text, (script, directive)
        assert f"petthm_job slurm/{script}.sbatch {scene} options/scenes/{scene}.opts" in text
