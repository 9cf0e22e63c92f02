"""Status words and exit codes (physics.md section 12, docs/user-guide/reliability.md
"Status"): 0 completed, 1 failed, 2 input error, 3 interrupted by a signal
or stopped by -thm_max_wall (continued with -thm_restart), 4 stopped by
-ts_max_steps (a limit the user set)."""
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from conftest import LAUWERIER_COARSE as LAUWERIER
from conftest import MPI_ENV, ROOT, checkpoint_state, ranks_of, read_json, read_text, run_petthm


def _state(folder):
    x, meta = checkpoint_state(folder)
    return x, float(meta["time"])


def test_max_steps_stops_with_exit_code_4_and_the_run_continues(tmp_path):
    proc, s = run_petthm(LAUWERIER[0], tmp_path / "a", *LAUWERIER[1:], "-thm_final_time", 1e6,
                         "-ts_max_steps", 7, check=False)
    assert proc.returncode == 4 and s["status"] == "stopped" and s["exit_code"] == 4
    assert "stopped by -ts_max_steps 7" in s["message"] and s["final_time"] < 1e6 and s["steps"] == 7
    _, s = run_petthm(LAUWERIER[0], tmp_path / "a", *LAUWERIER[1:], "-thm_final_time", 1e6,
                      "-thm_restart", tmp_path / "a")
    assert s["status"] == "completed" and s["final_time"] == 1e6


def test_max_wall_stops_with_a_checkpoint_and_exit_code_3_and_the_restart_is_the_uninterrupted_run(tmp_path):
    run_petthm(LAUWERIER[0], tmp_path / "ref", *LAUWERIER[1:], "-thm_final_time", 1e8)
    proc, s = run_petthm(LAUWERIER[0], tmp_path / "a", *LAUWERIER[1:], "-thm_final_time", 1e8,
                         "-thm_max_wall", 1e-9, check=False)
    assert proc.returncode == 3 and s["status"] == "stopped" and "-thm_max_wall" in s["message"], proc.stderr
    assert s["steps"] == 1 and _state(tmp_path / "a")[1] == s["final_time"]
    _, s = run_petthm(LAUWERIER[0], tmp_path / "a", *LAUWERIER[1:], "-thm_final_time", 1e8,
                      "-thm_restart", tmp_path / "a")
    x, t = _state(tmp_path / "a")
    x_ref, t_ref = _state(tmp_path / "ref")
    assert s["status"] == "completed" and t == t_ref
    assert np.abs(x - x_ref).max() <= 1e-10 * np.abs(x_ref).max()


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGUSR1"])
@pytest.mark.parametrize("ranks", [1, 2, 3])
def test_a_signal_to_the_ranks_checkpoints_and_exits_3(tmp_path, ranks, sig):
    """What srun sends (the signal to every rank): a checkpoint, status
    interrupted, exit code 3, on 1, 2 and 3 ranks."""
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "petthm", *map(str, LAUWERIER), "-thm_final_time", "1e8",
           "-thm_output_dir", str(out), "-thm_quiet", "-thm_checkpoint_interval", "0"]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    proc = subprocess.Popen(cmd, cwd=ROOT, env=dict(os.environ, **MPI_ENV), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    end = time.time() + 120
    while time.time() < end and proc.poll() is None and not (
            os.path.exists(out / "history.csv") and len(read_text(out / "history.csv").splitlines()) > 4):
        time.sleep(0.02)
    pids = ranks_of(proc.pid) if ranks > 1 else [proc.pid]
    assert len(pids) == ranks
    for pid in pids:
        os.kill(pid, getattr(signal, sig))
    stdout, stderr = proc.communicate(timeout=120)
    s = read_json(out / "summary.json")
    assert proc.returncode == 3, stdout + stderr
    assert s["status"] == "interrupted" and sig in s["message"] and "Traceback" not in stderr
    assert _state(out)[1] == s["final_time"] < 1e8


def test_a_shrinking_step_schedule_that_cannot_reach_the_end_is_refused(tmp_path):
    proc, _ = run_petthm(LAUWERIER[0], tmp_path, *LAUWERIER[1:], "-thm_final_time", 1e6,
                         "-thm_dt_growth", 0.5, check=False)
    err = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(err) == 1, proc.stderr
    assert "-thm_dt_growth = 0.5" in err[0] and "add up to at most 200 s" in err[0], err[0]
