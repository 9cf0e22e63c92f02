"""Disk and rank faults (docs/user-guide/reliability.md, "Disk and ranks"): no space
left at the start or in the middle of a run is a one-line error with exit
code 1 and the last checkpoint intact; after space is freed the restart
completes equal to the uninterrupted run; a kill -9 in the middle of a
checkpoint write leaves the previous checkpoint; more ranks than the mesh
has cells is a one-line error.

The disk is a small tmpfs mounted by the test where the machine lets it
(root in a container); elsewhere the file system's free space is reported
as none by tests/reliability/faults.py."""
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import LAUWERIER_COARSE, MPI_ENV, ROOT, checkpoint_state, run_petthm

HERE = os.path.dirname(os.path.abspath(__file__))
LAUWERIER = (*LAUWERIER_COARSE, "-thm_final_time", 1e7, "-thm_checkpoint_interval", 5)


def _state(folder):
    x, meta = checkpoint_state(folder)
    return x, float(meta["time"])


def _restart_ends_as(out, ref):
    """-thm_restart of ``out`` completes with the final state of the run in ``ref`` (1e-10)."""
    proc = _run([*LAUWERIER, "-thm_restart", out])
    assert proc.returncode == 0, proc.stderr
    x, t = _state(out)
    x_ref, t_ref = _state(ref)
    assert t == t_ref and np.abs(x - x_ref).max() <= 1e-10 * np.abs(x_ref).max()


def _folder_bytes(folder):
    return sum(os.path.getsize(os.path.join(folder, n)) for n in os.listdir(folder))


def _run(args, cwd=ROOT, faults=None):
    launch = (os.path.join(HERE, "faults.py"), *map(str, faults)) if faults else ("-m", "petthm")
    cmd = [sys.executable, *launch, *map(str, args), "-thm_quiet"]
    return subprocess.run(cmd, cwd=cwd, env=dict(os.environ, **MPI_ENV), capture_output=True, text=True,
                          timeout=600)


class SmallDisk:
    """A tmpfs of ``size`` bytes at ``path`` (unmounted at the end), or None
    where mounting is not allowed."""

    def __init__(self, path, size):
        self.path = path
        os.makedirs(path)
        ok = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
                            capture_output=True).returncode == 0
        self.mounted = ok

    def fill(self, leave):
        """Fill the disk to ``leave`` free bytes (a ballast file)."""
        st = os.statvfs(self.path)
        free = st.f_bavail * st.f_frsize
        with open(os.path.join(self.path, "ballast"), "wb") as f:
            f.write(b"\0" * max(0, free - leave))

    def free_space(self):
        os.remove(os.path.join(self.path, "ballast"))

    def close(self):
        if self.mounted:
            subprocess.run(["umount", str(self.path)], capture_output=True)


@pytest.fixture
def small_disk(tmp_path):
    disks = []

    def make(size):
        disks.append(SmallDisk(tmp_path / f"disk{len(disks)}", size))
        return disks[-1]
    yield make
    for d in disks:
        d.close()


def _one_line(proc, code=1):
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == code and len(lines) == 1 and lines[0].startswith("petthm: error: "), \
        proc.stdout + proc.stderr
    return lines[0]


def test_a_full_disk_at_the_start_is_a_one_line_error(small_disk, tmp_path):
    disk = small_disk(8 << 10)
    out = disk.path / "run"
    if disk.mounted:
        proc = _run([*LAUWERIER, "-thm_output_dir", out])
    else:
        proc = _run([*LAUWERIER, "-thm_output_dir", out], faults=("no-space", 1))
    assert "No space left on device" in _one_line(proc)


def test_a_disk_filling_mid_run_fails_cleanly_and_the_restart_completes(small_disk, tmp_path):
    """The disk fills after about half the run's output: one line, exit 1,
    the checkpoint readable; with space freed, -thm_restart completes to the
    uninterrupted run's final state (1e-10)."""
    run_petthm(LAUWERIER[0], tmp_path / "ref", *LAUWERIER[1:])
    total = _folder_bytes(tmp_path / "ref")
    disk = small_disk(4 * total + (4 << 20))
    out = disk.path / "run"
    if disk.mounted:
        disk.fill(leave=(1 << 18) + total // 2)
        proc = _run([*LAUWERIER, "-thm_output_dir", out])
    else:
        proc = _run([*LAUWERIER, "-thm_output_dir", out], faults=("no-space", 20))
    assert "No space left on device" in _one_line(proc) and "-thm_restart" in proc.stderr
    assert 0 < _state(out)[1] < 1e7
    if disk.mounted:
        disk.free_space()
    _restart_ends_as(out, tmp_path / "ref")


def test_kill_9_in_a_checkpoint_write_then_restart_gives_the_uninterrupted_run(tmp_path):
    """Killed (SIGKILL) while it writes its third checkpoint: the second one
    is intact, and -thm_restart ends equal to the uninterrupted run (serial,
    direct solve; 1e-10)."""
    run_petthm(LAUWERIER[0], tmp_path / "ref", *LAUWERIER[1:])
    out = tmp_path / "killed"
    proc = _run([*LAUWERIER, "-thm_output_dir", out], faults=("kill-in-checkpoint", 3))
    assert proc.returncode == -9
    assert (out / "checkpoint.h5.tmp").exists()
    assert _state(out)[1] > 0
    _restart_ends_as(out, tmp_path / "ref")


def test_more_ranks_than_cells_is_a_one_line_error(tmp_path):
    cmd = ["mpiexec", "-n", "3", sys.executable, "-m", "petthm", "heat_mms", "-thm_mesh_size", "1",
           "-thm_output_dir", str(tmp_path / "run"), "-thm_quiet"]
    proc = subprocess.run(cmd, cwd=ROOT, env=dict(os.environ, **MPI_ENV), capture_output=True, text=True,
                          timeout=300)
    mine = [line for line in proc.stderr.splitlines() if line.startswith("petthm")]   # not mpiexec's banner
    assert proc.returncode == 2 and len(mine) == 1, proc.stderr
    assert "cannot feed 3 ranks" in mine[0] and "Traceback" not in proc.stderr, mine[0]
