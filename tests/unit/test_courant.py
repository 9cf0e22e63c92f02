"""The temperature front's Courant number (``courant.front_courant``) and the
step limit it sets (``-thm_dt_courant``)."""
import numpy as np
import pytest

from conftest import build_problem, run_petthm
from petthm.discretisation.fields import Domain
from petthm.solvers.courant import FRONT, front_courant

T0 = 373.15


def _state(p, slope, shift=0.0):
    """A copy of the state with Tf (and the rock) a linear ramp along the
    fracture, T = T0 - slope (100 - x - shift): a front moved by ``shift``."""
    ramp = lambda x: T0 - slope * (100.0 - x[:, 0] - shift)     # noqa: E731
    p.set_initial({"Tf": ramp, "Tm": ramp})
    return p.X.copy()


@pytest.mark.parametrize("degree", [1, 2])
def test_front_courant_counts_the_cells_a_ramp_moved(tmp_path, degree):
    p = build_problem(tmp_path, "lauwerier", thm_fe_degree=degree, thm_lauwerier_fracture_size=4.0,
                      thm_mesh_size=20.0)
    h = p.disc.regions[Domain.FRACTURE].h
    X0 = _state(p, 0.7)
    X1 = _state(p, 0.7, shift=1.0)
    X2 = _state(p, 0.7, shift=2.0)
    assert 0.7 * h.min() / 80.0 >= FRONT                        # every fracture cell holds the front
    assert front_courant(p, X0, X1, 0.0) == pytest.approx(1.0 / h.min(), rel=1e-9)
    assert front_courant(p, X0, X2, 0.0) == pytest.approx(2.0 / h.min(), rel=1e-9)
    # negative controls: no change, and a change where no cell holds a front (0.4 % across a cell)
    assert front_courant(p, X0, X0, 0.0) == 0.0
    flat0, flat1 = _state(p, 0.08), _state(p, 0.08, shift=1.0)
    assert 0.08 * h.max() / 80.0 < FRONT
    assert front_courant(p, flat0, flat1, 0.0) == 0.0


def test_courant_limit_takes_more_and_more_accurate_steps(tmp_path):
    """lauwerier P1 (fracture 2 m) with SUPG: the limit adds steps where the
    front moves fast, and lowers the outlet error (measured: 184 -> 274 steps,
    3.47 -> 1.62 K from 1e6 s on with 0.5 cells per step).  With the default
    limited scheme this coarse rock's lumped capacity sets the error (0.30 of
    the range either way; manual, theory: discrete bounds)."""
    opts = ("-thm_fe_degree", 1, "-thm_heat_transport", "supg", "-thm_lauwerier_fracture_size", 2,
            "-thm_mesh_size", 15, "-thm_dt_max", 2e6, "-thm_dt_growth", 1.07)
    _, free = run_petthm("lauwerier", tmp_path / "free", *opts)
    _, limited = run_petthm("lauwerier", tmp_path / "limited", *opts, "-thm_dt_courant", 0.5)
    assert limited["steps"] > 1.3 * free["steps"]
    e_free, e_lim = (s["error"]["outlet_max_rel_t_ge_1e6"] for s in (free, limited))
    assert e_lim < 0.7 * e_free
    assert np.isfinite(limited["balance_max"]["energy_balance"])
