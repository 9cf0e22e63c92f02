"""Coulomb friction (issue 13): the friction law's Jacobian, the
friction_patch scene (stick, slip and the step between them; P1/P2, 2D/3D,
serial = 2 ranks), stiff cases, and friction switched on where the
reference solution has no shear."""

import numpy as np
import pytest

from conftest import build_problem, read_csv, read_json
from petthm.verification.jacobian import jacobian_fd_block_errors

FRICTION_BLOCKS = [("tau", "tau"), ("tau", "lam"), ("tau", "u"), ("u", "tau")]


def _friction_problem(tmp_path, dim, degree):
    return build_problem(tmp_path, "friction_patch", thm_friction_dim=dim, thm_fe_degree=degree,
                         thm_mesh_size=5)


@pytest.mark.parametrize("dim,degree", [(2, 2), (3, 1), (3, 2)])
@pytest.mark.parametrize("state,shift", [("stick", 1e8), ("slip", 1e-3)])
def test_friction_jacobian_matches_finite_differences(tmp_path, dim, degree, state, shift):
    """At a random state the slip increment ds = s_dot / shift is tiny for a
    large shift (every node sticks: |tau - c ds| < b) and huge for a small
    one (every node slips); away from the switch each friction block
    matches central differences to 1e-6.  Zero blocks: in stick C = c ds
    (no tau, lam); in 2D slip C = tau - b sign(z) (no u)."""
    problem = _friction_problem(tmp_path, dim, degree)
    err = jacobian_fd_block_errors(problem, t=0.5, shift=shift, eps=(1e-6, 1e-7))
    print(state, {k: f"{v:.1e}" for k, v in err.items() if "tau" in k})
    zero = [("tau", "tau"), ("tau", "lam")] if state == "stick" else [("tau", "u")] if dim == 2 else []
    for block in FRICTION_BLOCKS:
        if block in zero:
            assert block not in err
        else:
            assert err[block] <= 1e-6, (block, err[block])


def test_friction_jacobian_check_detects_a_missing_block(tmp_path):
    """Negative control: without d(law)/d(lam) the slip state's check fails."""
    problem = _friction_problem(tmp_path, 3, 1)
    from petthm.discretisation.model import FRACTURE_NODAL
    asm = problem.region(FRACTURE_NODAL)
    asm.model.jacobians[:] = [j for j in asm.model.jacobians if not (j.test == "tau" and j.trial == "lam")]
    asm.build_pattern()
    problem.J = None
    err = jacobian_fd_block_errors(problem, t=0.5, shift=1e-3, eps=1e-6)
    assert err[("tau", "lam")] > 1e-2, err


def _summary(path):
    return read_json(path / "summary.json")


@pytest.mark.parametrize("dim,degree", [(2, 1), (2, 2), (3, 1), (3, 2)])
def test_friction_patch_stick_then_slip(tmp_path, petthm_run, dim, degree):
    """Shear ramped to twice the slip threshold in 5 steps: steps 1-2 stick
    (slip <= 1e-12 m), step 3 takes the whole fracture from stick to slip,
    steps 3-5 slip with |tau| = mu_f lam (1e-8) and the exact uniform slip
    and traction."""
    _, s = petthm_run("friction_patch", tmp_path, "-thm_friction_dim", dim, "-thm_fe_degree", degree)
    e = s["error"]
    print(dim, degree, e)
    assert s["status"] == "completed" and s["rejected_steps"] == 0
    assert e["stick_slip_max"] <= 1e-12 and e["law_error"] <= 1e-8
    assert e["slip_error"] <= 1e-9 * s["slip_exact_final"]
    assert e["tau_error"] <= 1e-8 and e["lam_error"] <= 1e-10
    assert s["slip_final"] == pytest.approx(s["slip_exact_final"], rel=1e-8) and s["slip_exact_final"] > 0


def test_friction_patch_below_the_bound_sticks(tmp_path, petthm_run):
    """Final shear at 0.9 of the bound: no slip at any step (<= 1e-12 m)."""
    _, s = petthm_run("friction_patch", tmp_path, "-thm_friction_dim", 3, "-thm_friction_shear_ratio", 0.9)
    assert s["status"] == "completed" and s["slip_exact_final"] == 0.0
    assert s["slip_final"] <= 1e-12 and s["error"]["tau_error"] <= 1e-8


@pytest.mark.parametrize("opts", [("-thm_fracture_friction", 1.0),
                                  ("-thm_fracture_friction", 0.0, "-thm_fracture_cohesion", 5e6)],
                         ids=["mu1", "mu0_cohesion"])
def test_friction_patch_stiff_coefficients(tmp_path, petthm_run, opts):
    """mu_f = 1 (2D P2), and mu_f = 0 with a cohesion only (the law's bound
    without lam): stick, then slip at |tau| = b."""
    _, s = petthm_run("friction_patch", tmp_path, *opts)
    e = s["error"]
    assert s["status"] == "completed"
    assert e["stick_slip_max"] <= 1e-12 and e["law_error"] <= 1e-8
    assert e["slip_error"] <= 1e-9 * s["slip_exact_final"]


def test_friction_patch_two_ranks_equal_serial(tmp_path, petthm_run):
    """3D P2 on 2 ranks: the same history as the serial run (1e-12 of the slip)."""
    _, s1 = petthm_run("friction_patch", tmp_path / "np1", "-thm_friction_dim", 3)
    _, s2 = petthm_run("friction_patch", tmp_path / "np2", "-thm_friction_dim", 3, ranks=2)
    h1 = (read_csv(tmp_path / "np1" / "history.csv"))
    h2 = (read_csv(tmp_path / "np2" / "history.csv"))
    assert len(h1) == len(h2)
    for a, b in zip(h1, h2, strict=False):
        assert abs(float(a["slip_max"]) - float(b["slip_max"])) <= 1e-12 * max(s1["slip_exact_final"], 1e-300)
    assert s2["error"]["law_error"] <= 1e-8 and s2["error"]["stick_slip_max"] <= 1e-12


@pytest.mark.parametrize("stiffness", [1e8, 1e14])
def test_friction_on_a_closed_patch_with_stiff_joints(tmp_path, petthm_run, stiffness):
    """contact_patch (no shear) with friction on and Kn from 1e8 to 1e14
    Pa/m: the frictionless result (lam = sigma - p, zero opening)."""
    _, s = petthm_run("contact_patch", tmp_path, "-thm_fracture_friction", 0.6,
                      "-thm_fracture_normal_stiffness", stiffness)
    assert s["status"] == "completed"
    assert s["error"]["lam_error"] <= 1e-10 and s["error"]["opening_max"] <= 1e-9


def test_friction_where_there_is_no_shear_changes_nothing(tmp_path, petthm_run):
    """partial_opening (mirror-symmetric about the crack) with mu_f = 0.6
    against frictionless: the same opening profile and open zone (the
    unstructured mesh is not exactly symmetric: 1e-6 of the opening,
    measured)."""
    _, a = petthm_run("partial_opening", tmp_path / "mu0", "-thm_partial_crack_size", 0.05)
    _, b = petthm_run("partial_opening", tmp_path / "mu06", "-thm_partial_crack_size", 0.05,
                      "-thm_fracture_friction", 0.6)
    ga, gb = np.array(a["profile"]["opening"]), np.array(b["profile"]["opening"])
    print("opening difference", np.abs(ga - gb).max(), "of", ga.max())
    assert a["open_length"] == b["open_length"]
    assert np.abs(ga - gb).max() <= 1e-5 * ga.max()


def test_inclined_crack_slip_converges_to_the_mode_ii_profile(tmp_path, petthm_run):
    """The frictional crack at 45 degrees in uniaxial compression (mu_f 0.6:
    driving stress 0.2 sigma) on crack meshes a/10, a/20, a/40 (P2): the
    relative L2 error of the slip over |x| < 0.95 a falls with every
    refinement and is below 5 % on the finest (measured 3.6, 1.6, 0.89 %;
    the clamped box at 20 a leaves a floor of about 0.6 %, as for Sneddon);
    |tau| = mu_f lam at every slipping node to 1e-8 (measured 3e-14)."""
    errors = []
    for h in (0.1, 0.05, 0.025):
        _, s = petthm_run("inclined_crack", tmp_path / str(h), "-thm_inclined_crack_size", h)
        errors.append(s["slip_l2_error"])
        assert s["status"] == "completed"
        assert s["slip_centre"] == pytest.approx(s["slip_centre_exact"], rel=0.05)
        assert s["law_error"] <= 1e-8
    print("slip L2 errors", errors)
    assert errors[0] > errors[1] > errors[2] and errors[2] < 0.05


def test_fracture_outputs_carry_slip_and_coulomb(tmp_path, petthm_run):
    """fracture.xdmf/.h5 carry the opening, the slip vector and magnitude,
    the shear traction and the Coulomb function (0 where slipping, < 0
    stuck); history.csv the largest slip and the slipping area (the whole
    100 m2 fracture once it slips)."""

    import h5py
    _, s = petthm_run("friction_patch", tmp_path, "-thm_friction_dim", 3, "-thm_fe_degree", 1)
    with h5py.File(tmp_path / "fracture.h5") as f:
        names = set(f["fields"])
        last = str(len(f["fields/slip"]) - 1)
        slip = f["fields/slip_magnitude/" + last][()]
        coulomb = f["fields/coulomb/" + last][()]
    assert {"opening", "slip", "slip_magnitude", "shear_traction", "coulomb", "tau", "lam"} <= names
    assert np.allclose(slip, s["slip_exact_final"], rtol=1e-8)
    assert np.abs(coulomb).max() <= 1e-8 * 0.6 * 60e6
    h = (read_csv(tmp_path / "history.csv"))
    assert float(h[-1]["slipping_area"]) == pytest.approx(100.0, rel=1e-12)
    assert float(h[1]["slipping_area"]) == 0.0 and float(h[-1]["slip_max"]) == pytest.approx(
        s["slip_exact_final"], rel=1e-8)


@pytest.mark.slow
def test_inclined_penny_crack_slip_converges(tmp_path, petthm_run):
    """The 3D counterpart (a penny crack dipping 45 degrees, half model, P2)
    on crack meshes a/5, a/10, a/20: the relative L2 error of the slip along
    the in-situ shear falls with every refinement and is below 5 % on the
    finest (measured 10.1, 4.7, 2.2 %; 31, 44, 101 s)."""
    errors = []
    for h in (0.2, 0.1, 0.05):
        _, s = petthm_run("inclined_crack", tmp_path / str(h), "-thm_inclined_dim", 3,
                          "-thm_inclined_crack_size", h, timeout=1800)
        assert s["status"] == "completed" and s["law_error"] <= 1e-8
        errors.append(s["slip_l2_error"])
    print("penny slip L2 errors", errors)
    assert errors[0] > errors[1] > errors[2] and errors[2] < 0.05


def test_inclined_crack_two_ranks_equal_serial(tmp_path, petthm_run):
    """2D, a/20, on 2 ranks: the serial slip error, centre slip and
    slipping area (each node counted once over the ranks)."""
    _, s1 = petthm_run("inclined_crack", tmp_path / "np1")
    _, s2 = petthm_run("inclined_crack", tmp_path / "np2", ranks=2)
    for k in ("slip_l2_error", "slip_centre", "slipping_area"):
        assert s2[k] == pytest.approx(s1[k], rel=1e-9), k
