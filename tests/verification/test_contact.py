"""Fracture mechanics (issue 4): face loads, contact with SNES's VI Newton,
Sneddon's crack openings, the contact patch test and partial opening."""

import numpy as np
import pytest

from conftest import build_problem, read_csv, solved_problem
from petthm.physics.monitors import recovered_traction
from petthm.verification.jacobian import jacobian_fd_error

SNEDDON_2D = ("-thm_sneddon_dim", 2, "-thm_sneddon_radius", 50, "-thm_sneddon_crack_size", 0.025)


@pytest.mark.parametrize("degree", [1, 2])
@pytest.mark.parametrize("scene,opts", [
    ("partial_opening", dict(thm_partial_crack_size=0.1)),
    ("contact_patch", dict(thm_contact_dim=3, thm_mesh_size=5)),
])
def test_contact_jacobian_matches_finite_differences(tmp_path, scene, opts, degree):
    """u+/u- against lam (face load) and lam against u+/u- (opening)."""
    problem = build_problem(tmp_path, scene, thm_fe_degree=degree, **opts)
    err = jacobian_fd_error(problem, t=0.5, shift=1.0, eps=1e-6)
    print(scene, degree, "jacobian fd error", err)
    assert err <= 1e-6, err


def test_contact_jacobian_check_detects_a_missing_block(tmp_path):
    """Negative control: without the lam-u+ block the check fails."""
    problem = build_problem(tmp_path, "partial_opening", thm_partial_crack_size=0.1)
    from petthm.discretisation.model import FRACTURE_DUAL, Side, Trace
    asm = problem.region(FRACTURE_DUAL)
    asm.model.jacobians[:] = [j for j in asm.model.jacobians
                              if not (j.test == "lam" and j.trial == Trace("u", Side.PLUS))]
    asm.build_pattern()
    problem.J = None
    err = jacobian_fd_error(problem, t=0.5, shift=1.0, eps=1e-6)
    assert err > 1e-3, err


@pytest.mark.parametrize("opts", [SNEDDON_2D, pytest.param((), marks=pytest.mark.first_pass_only)],
                         ids=["griffith_2d", "penny_3d"])
def test_sneddon_opening(tmp_path, petthm_run, opts):
    """verification.md section 4: w(0) within 2 %, L2 over r < 0.95 R within 3 %."""
    _, s = petthm_run("sneddon", tmp_path, *opts)
    e = s["error"]
    print("sneddon", opts[:2], e)
    assert s["status"] == "completed"
    assert e["centre_error"] <= 2e-2 and e["opening_l2_error"] <= 3e-2


def test_sneddon_nearly_incompressible(tmp_path, petthm_run):
    """Stiff case nu = 0.49 (P2 displacement): converges, no NaN, opening
    within 2 % once the clamped boundary is far (the 2D far-field error
    falls like c/L here: 5 % at L = 20 c, 1.2 % at 80 c)."""
    _, s = petthm_run("sneddon", tmp_path, *SNEDDON_2D, "-thm_rock_poisson_ratio", 0.49, "-thm_sneddon_box",
                      80)
    print("nu = 0.49", s["error"])
    assert s["status"] == "completed" and s["error"]["centre_error"] <= 2e-2


@pytest.mark.parametrize("dim,degree", [(2, 1), (2, 2), (3, 1), (3, 2)])
def test_contact_patch_is_exact(tmp_path, petthm_run, dim, degree):
    """verification.md section 5: lam = sigma - p at every vertex and step, no
    opening, aperture a0 - lam/Kn = 0.2 mm at sigma = 60, p = 20 MPa."""
    _, s = petthm_run("contact_patch", tmp_path, "-thm_contact_dim", dim, "-thm_fe_degree", degree)
    e = s["error"]
    print(dim, degree, e, s["aperture_mean"])
    assert s["status"] == "completed"
    assert e["lam_error"] <= 1e-6 and e["opening_max"] <= 1e-9 and e["aperture_error"] <= 1e-10
    assert e["lam_recovered_error"] <= 1e-6
    assert abs(s["aperture_mean"] - 0.2e-3) <= 1e-10 * 0.2e-3


def test_recovered_traction_is_exact_on_the_patch_and_needs_every_term(tmp_path):
    """The traction recovered from the rock's stress
    (kernels/contact.RecoveredTraction, monitors.recovered_traction) is
    sigma - p at every node at the end of the ramp (2D P1); negative controls: recovered with a rock twice as
    stiff, or without the fluid's load, it is off by more than 10 %."""
    import dataclasses
    scene, problem = solved_problem(tmp_path, "contact_patch", thm_contact_dim=2)
    t, rt = scene.final_time, problem.model.recovered_traction
    exact = scene.exact_lam(t)

    def error(recovery):
        return np.abs(recovered_traction(problem, t=t, recovery=recovery) - exact).max() / exact
    stiff = dataclasses.replace(rt, elastic=dataclasses.replace(rt.elastic,
                                                                youngs_modulus=2 * rt.elastic.youngs_modulus))
    dry = dataclasses.replace(rt, mech=dataclasses.replace(rt.mech, pressure=None))
    print("recovered traction errors: exact", error(rt), "stiff", error(stiff), "dry", error(dry))
    assert error(rt) <= 1e-12
    assert error(stiff) > 0.1 and error(dry) > 0.1


@pytest.mark.parametrize("sigma,kn,aperture",
                         [(75e6, 1e11, 0.05e-3), (60e6, 1e8, 0.6e-6), (60e6, 1e14, 0.5996e-3)])
def test_contact_patch_joint_stiffness(tmp_path, petthm_run, sigma, kn, aperture):
    """0.05 mm at 75/20 MPa; the stiff and soft extremes Kn = 1e8 (the
    residual aperture 1e-3 a0) and 1e14 Pa/m."""
    _, s = petthm_run("contact_patch", tmp_path, "-thm_contact_dim", 2, "-thm_insitu_stress", sigma,
                      "-thm_fracture_normal_stiffness", kn)
    e = s["error"]
    assert s["status"] == "completed"
    assert e["lam_error"] <= 1e-6 and e["opening_max"] <= 1e-9 and e["aperture_error"] <= 1e-10
    assert abs(s["aperture_mean"] - aperture) <= 1e-10 * aperture


def test_partial_opening_both_vi_methods(tmp_path, petthm_run):
    """Open centre, closed rim; the active set changes over the steps; both VI
    Newton methods give the same state."""
    res = {}
    for t in ("vinewtonrsls", "vinewtonssls"):
        _, s = petthm_run("partial_opening", tmp_path / t, "-thm_partial_crack_size", 0.05, "-snes_type", t)
        assert s["status"] == "completed"
        res[t] = s
    a, b = res["vinewtonrsls"], res["vinewtonssls"]
    print({k: (a[k], b[k]) for k in ("open_length", "opening_centre", "nodes_open")})
    c = 50.0
    assert 0.5 * c < a["open_length"] < c and 0 < a["nodes_open"] < len(a["profile"]["x"])
    assert a["open_length"] == b["open_length"] and a["nodes_open"] == b["nodes_open"]
    assert abs(a["opening_centre"] - b["opening_centre"]) <= 1e-8 * a["opening_centre"]


def test_contact_needs_a_vi_solver(tmp_path, petthm_run):
    """A Newton method that ignores the bounds is refused with a one-line error."""
    proc, _ = petthm_run("contact_patch", tmp_path, "-thm_contact_dim", 2, "-snes_type", "newtonls",
                         check=False)
    out = proc.stdout + proc.stderr
    print(out)
    assert proc.returncode != 0 and "Traceback" not in out
    assert "vinewtonrsls" in out and "-snes_type newtonls" in out


@pytest.mark.parametrize("degree", [1, 2])
def test_deformable_flow_jacobian_matches_finite_differences(tmp_path, degree):
    """Fracture flow with a = ac(lam) + max(g, 0): pf against pf, lam, u+, u-
    (da/dt, a c_f dp/dt, a^3 in the cubic law), and the face load against pf."""
    problem = build_problem(tmp_path, "fracture_inflation", thm_fe_degree=degree, thm_partial_crack_size=0.1,
                            thm_fluid_compressibility=4.5e-10)
    err = jacobian_fd_error(problem, t=100.0, shift=0.1, eps=1e-6)
    print(degree, "jacobian fd error", err)
    assert err <= 1e-6, err


def test_fracture_inflation_opens_at_the_closure_stress(tmp_path, petthm_run):
    """Injection into a closed crack: the pressure rises while the joint
    compresses less, levels off just above the closure stress (10 MPa) once
    the crack opens; the injected volume equals the change of int a
    (incompressible fluid) to 2e-4."""
    out, s = petthm_run("fracture_inflation", tmp_path)
    h = (read_csv(tmp_path / "history.csv"))[1:]
    p = np.array([float(r["injection_pressure"]) for r in h])
    bal = np.array([abs(float(r["volume_balance"])) for r in h])
    print("pressure", p[[0, len(p) // 2, -1]], "volume balance max", bal.max())
    assert s["status"] == "completed" and s["nodes_open"] > 1
    assert np.all(np.diff(p) > 0) and 10e6 < p[-1] < 10.2e6
    assert bal.max() <= 2e-4
