"""``checkpoint.truncate_history``: a restart keeps the history rows up to
its checkpoint, the checkpoint's own row included, whatever the rounding of
the times history.csv writes (12 significant digits)."""
import csv

from mpi4py import MPI

from petthm.io.checkpoint import truncate_history
from petthm.io.output import History


def _times(path):
    with open(path, newline="") as f:
        return [float(r[1]) for r in list(csv.reader(f))[1:]]


def test_the_checkpoints_row_is_kept_when_its_time_is_rounded_up(tmp_path):
    """1102.6564319570314 s is written 1102.65643196, 2.7e-12 above it (the
    case a kill -9 restart test hit): the row stays, the next one goes.  The
    negative control: the former tolerance t (1 + 1e-12) drops it."""
    path = str(tmp_path / "history.csv")
    t_ckpt = 1102.6564319570314
    h = History(path, ["step", "time"], MPI.COMM_SELF)
    for step, t in enumerate([954.910887578, t_ckpt, 1257.789253554883]):
        h.write({"step": step, "time": t})
    h.close()
    assert _times(path)[1] > t_ckpt * (1 + 1e-12)           # what the old rule dropped
    truncate_history(path, t_ckpt)
    assert _times(path) == [954.910887578, 1102.65643196]


def test_rows_after_the_checkpoint_go(tmp_path):
    path = str(tmp_path / "history.csv")
    h = History(path, ["step", "time"], MPI.COMM_SELF)
    for step, t in enumerate([0.0, 100.0, 205.0, 315.25]):
        h.write({"step": step, "time": t})
    h.close()
    truncate_history(path, 205.0)
    assert _times(path) == [0.0, 100.0, 205.0]
