"""The full coupled manufactured solution (coupled_mms, verification.md section 8):
every field of Scene 3 at once.  The 2D cases run here, and one 3D pair (the
closed aperture's order); the 3D rates are in benchmarks/studies/coupled_mms_study.py
(benchmarks/results/coupled_mms*)."""
import dataclasses

import numpy as np
import pytest

from conftest import build_problem, fitted_slope, run_petthm

FIELDS = ("u", "lam", "pf", "pm", "Tf", "Tm")
MIN_SLOPE = {(1, "l2"): 1.8, (1, "h1"): 0.9, (2, "l2"): 2.8, (2, "h1"): 1.8}


def _rates(tmp_path, sizes, *opts):
    hs, err = [], {f: {"l2": [], "h1": []} for f in FIELDS + ("lam_recovered",)}
    for k, size in enumerate(sizes):
        _, s = run_petthm("coupled_mms", tmp_path / f"r{k}", "-thm_mesh_size", size, *opts)
        assert s["status"] == "completed"
        hs.append(s["h_max"])
        for f in FIELDS + ("lam_recovered",):
            for n in ("l2", "h1"):
                err[f][n].append(s["error"][f"{f}_{n}"])
    return hs, err


@pytest.mark.parametrize("degree,state,supg,sizes", [
    (1, "open", 1, (0.125, 0.0625, 0.03125, 0.015625)),       # SUPG (-thm_heat_transport supg)
    (1, "open", "limited", (0.125, 0.0625, 0.03125, 0.015625)),  # the flux-corrected upwinding (P1's default)
    (2, "closed", 0, (0.25, 0.125, 0.0625, 0.03125)),         # P2, Galerkin heat, contact closed
    (2, "open", "wall", (0.25, 0.125, 0.0625)),               # P2, SUPG with the rock's wall conduction
])
def test_coupled_mms_rates(tmp_path, degree, state, supg, sizes):
    """Optimal rates of every field.  P2 with SUPG needs the rock's wall
    conduction in the fracture's SUPG residual (-thm_fracture_supg_wall_conduction):
    without it Tf and Tm stop at L2 slope 2.2 (docs/verification/coupled-mms.md, point 3).
    The limited scheme's stored energy counts the water's content (the
    manufactured sources too: its energy is cubic in t on the fracture)."""
    wall = {"wall": ("-thm_fracture_supg_wall_conduction", "true"), 1: ("-thm_heat_transport", "supg"),
            "limited": ("-thm_heat_transport", "limited")}.get(supg, ())
    hs, err = _rates(tmp_path, sizes, "-thm_coupled_mms_dim", 2, "-thm_fe_degree", degree,
                     "-thm_coupled_mms_state", state, "-thm_coupled_mms_supg", int(bool(supg)), *wall)
    for f in FIELDS:
        if f == "lam":
            continue
        l2, h1 = err[f]["l2"], err[f]["h1"]
        assert all(np.diff(l2) < 0) and all(np.diff(h1) < 0), (f, l2, h1)
        sl2, sh1 = fitted_slope(hs, l2), fitted_slope(hs, h1)
        print(f"coupled_mms 2D P{degree} {state} supg={supg} {f}: L2 slope {sl2:.2f}, H1 slope {sh1:.2f}")
        assert sl2 >= MIN_SLOPE[(degree, "l2")], (f, sl2)
        assert sh1 >= MIN_SLOPE[(degree, "h1")], (f, sh1)
    if state == "open":
        assert max(err["lam"]["l2"]) == 0.0          # the fracture stays open: lam = 0 exactly
    else:
        # lam is a traction (a derivative of u): its nodal values converge as the stress, h^p, and so
        # does the traction recovered from the rock's stress (kernels/contact.RecoveredTraction)
        for f in ("lam", "lam_recovered"):
            sl = fitted_slope(hs, err[f]["l2"])
            print(f"coupled_mms 2D P{degree} closed {f}: L2 slope {sl:.2f}")
            assert sl >= degree - 0.2 and all(np.diff(err[f]["l2"]) < 0)


@pytest.mark.slow             # 3D P2 on two meshes for two joints: ~95 s; make test-slow
def test_the_closed_fractures_fields_converge_at_the_order_of_its_aperture(tmp_path):
    """3D P2, fracture closed: a = a0 - lam/Kn carries the contact traction's
    error (order h^2, a stress's) into the cubic law and the fracture's
    capacity.  With the manufactured joint soft (Kn = 2: lam moves a by up to
    half of a0) pf and Tf converge at lam's order; with it stiff (Kn = 200,
    the same solution otherwise) at the optimal order 3.  Two meshes
    (h 0.50 -> 0.25; docs/verification/coupled-mms.md, "The closed fracture's aperture"
    for three: pf 3.19, Tf 3.50 against 2.00, 1.83)."""
    def slopes(kn):
        hs, err = _rates(tmp_path / f"kn{kn}", (0.25, 0.125), "-thm_coupled_mms_dim", 3, "-thm_fe_degree", 2,
                         "-thm_coupled_mms_state", "closed", "-thm_coupled_mms_supg", 0,
                         "-thm_fracture_normal_stiffness", kn, "-thm_direct_max_unknowns", 1000000)
        return {f: fitted_slope(hs, err[f]["l2"]) for f in ("pf", "Tf", "lam")}   # lam: printed only
    stiff, soft = slopes(200), slopes(2)
    print("coupled_mms 3D P2 closed, L2 slopes: Kn = 200", stiff, "Kn = 2", soft)
    assert stiff["pf"] >= 2.8 and stiff["Tf"] >= 2.8
    assert soft["pf"] < 2.2 and soft["Tf"] < 2.2              # the channel: lam's order, measured 1.86 / 1.48


def _consistency(tmp_path, size, **opts):
    """max |scaled residual| per field of the interpolated exact solution at t = 1 (P1)."""
    from petsc4py import PETSc

    from petthm.run.driver import make_scene
    from petthm.scenes.base import on_sides
    P = build_problem(tmp_path, "coupled_mms", thm_mesh_size=size, thm_fe_degree=1, thm_coupled_mms_supg=0,
                      **opts)
    m = make_scene("coupled_mms").solution(2)

    def state(fn):
        out = {f: (lambda x, f=f: fn(f)(x, 1.0)) for f in FIELDS if f != "u"}
        out["u"] = on_sides(lambda x, inside: fn("u")(x, 1.0, inside))
        return out
    P.set_initial(state(m.value))
    X = P.X.copy()
    P.set_initial(state(m.rate))
    xl = P._Xl.getArray()
    for f in FIELDS:                   # a rate has no offset
        xl[P.disc.field_local_dofs(f)] += P.scales[f].offset / P.scales[f].scale
    Xd = X.duplicate()
    P.dm.localToGlobal(P._Xl, Xd, addv=PETSc.InsertMode.INSERT_VALUES)
    F = X.duplicate()
    P.residual_shift = 2.0
    P.ifunction(None, 1.0, X, Xd, F)
    Fl = P.dm.createLocalVec()
    P.dm.globalToLocal(F, Fl)
    r = Fl.getArray()
    held = np.zeros(len(r), dtype=bool)
    held[P.constraints.constrained_local()] = True
    out = {}
    for f in ("u", "pf", "pm", "Tf", "Tm"):
        d = P.disc.field_local_dofs(f).ravel()
        out[f] = float(np.abs(r[d[~held[d]]]).max())
    return out


def test_interpolated_exact_solution_is_consistent(tmp_path, monkeypatch):
    """The discrete residual of the exact solution's interpolant falls with h
    in every equation (the sources are the simulator's own operator, and the
    two copies of a node on the fracture take their sides' values); with a
    Biot coefficient off by 10 % between sources and operator (negative
    control) the u rows fall far more slowly."""
    a, b = (_consistency(tmp_path / f"c{k}", s) for k, s in enumerate((0.0625, 0.03125)))
    print("consistency", a, b)
    assert all(b[f] < 0.4 * a[f] for f in a), (a, b)
    # negative control: the operator's Biot coefficient 10 % above the one the sources were made with
    import petthm.scenes.coupled_mms as cm
    made = cm.coefficients

    def sources_with_alpha_08(p, dim, *more):
        return dataclasses.replace(made(p, dim, *more), alpha=0.8)
    monkeypatch.setattr(cm, "coefficients", sources_with_alpha_08)
    bad = [_consistency(tmp_path / f"n{k}", s, thm_rock_biot_coefficient=0.88)
           for k, s in enumerate((0.0625, 0.03125))]
    print("negative control", bad)
    # the u rows of the inconsistent operator fall at most half as fast, and its gap to the
    # consistent one widens with refinement
    assert bad[1]["u"] > 0.4 * bad[0]["u"], bad
    assert bad[1]["u"] / b["u"] > 2 * bad[0]["u"] / a["u"], (bad, a, b)


@pytest.mark.parametrize("degree", [1, 2])
def test_coupled_mms_jacobian_blocks_match_finite_differences(tmp_path, degree):
    """Every block of the coupled operator with SUPG, its T div b from the
    mass balance included (Tm-u through alpha d(div u)/dt, Tm-pm and Tf-pf
    through the storage, Tf-lam and Tf-u through the aperture), against
    central differences at a random state and rate."""
    from petthm.verification.jacobian import jacobian_fd_block_errors
    problem = build_problem(tmp_path, "coupled_mms", thm_fe_degree=degree, thm_mesh_size=0.25,
                            thm_coupled_mms_state="closed")
    err = jacobian_fd_block_errors(problem, t=0.5, shift=2.0, eps=(1e-6, 1e-4))
    print(degree, {f"{a}-{b}": float(f"{v:.2g}") for (a, b), v in err.items()})
    assert {("Tm", "u"), ("Tm", "pm"), ("Tf", "pf"), ("Tf", "lam"), ("Tf", "u"), ("pf", "lam")} <= set(err)
    assert max(err.values()) <= 1e-6


def test_coupled_mms_jacobian_check_can_fail(tmp_path, monkeypatch):
    """Negative control: without the SUPG block of alpha d(div u)/dt the Tm-u block is wrong
    (SUPG's: P1 temperatures take the limited scheme by default)."""
    from petthm.physics.kernels import heat as hk
    from petthm.verification.jacobian import jacobian_fd_block_errors
    monkeypatch.setattr(hk, "heat_g3_Tu", lambda h, ctx: np.zeros((1, 1, 1, 2, 2, 2)))     # 2D
    problem = build_problem(tmp_path, "coupled_mms", thm_fe_degree=1, thm_mesh_size=0.25,
                            thm_heat_transport="supg")
    err = jacobian_fd_block_errors(problem, t=0.5, shift=2.0, eps=1e-6)
    assert err[("Tm", "u")] > 1e-3
    assert err[("pm", "u")] <= 1e-6
