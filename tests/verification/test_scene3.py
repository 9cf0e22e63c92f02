"""Scene 3 (inclined_penny): matrix wells (the injected volume is Q t, the
interval's vertices carry the rate), the Jacobian of the whole operator
against finite differences, a short coarse run (initial state exact,
balances, a = a0 - lam/Kn where closed), the clean stop of a producer
drawn below zero pressure."""
import csv

import numpy as np
import pytest

from conftest import build_problem
from petthm.errors import InputError
from petthm.physics.matrixwells import Perforation, interval_nodes, lumped_weights
from petthm.verification.jacobian import jacobian_fd_block_errors

#: the coarse variant's mesh (options/scenes/inclined_penny_coarse.opts)
COARSE = dict(thm_scene3_fracture_size=50, thm_scene3_well_size=15, thm_mesh_size=300)
ARGS = [x for k, v in COARSE.items() for x in (f"-{k}", v)]
#: every block of the operator that couples two fields of Scene 3
COUPLINGS = {("u", "lam"), ("lam", "u"), ("u", "pm"), ("u", "Tm"), ("pm", "u"), ("pf", "lam"), ("pf", "u"),
             ("pf", "Tf"), ("pf", "pm"), ("pm", "pf"), ("Tm", "pm"), ("Tf", "pf"), ("Tf", "u"), ("Tf", "lam")}


def test_lumped_weights_are_the_line_shares():
    """Half of each adjacent spacing, over the length: they sum to one."""
    w = lumped_weights(np.array([0.0, 5.0, 10.0, 20.0]), 20.0)
    assert np.allclose(w, [0.125, 0.25, 0.375, 0.25])
    assert abs(w.sum() - 1.0) < 1e-15


def test_wells_sit_on_the_embedded_interval(tmp_path):
    """The generated mesh has vertices along both perforations, from end to
    end; an interval that is not a line of the mesh is a one-line error."""
    problem = build_problem(tmp_path, "inclined_penny", thm_fe_degree=1, **COARSE)
    mesh = problem.disc.mesh
    nodes = interval_nodes(mesh, Perforation("injector", (0.0, -150.0, 10.0), (0.0, -150.0, 30.0)))
    z = [n.point[2] for n in nodes]
    assert z[0] == pytest.approx(10.0) and z[-1] == pytest.approx(30.0) and len(z) >= 2
    assert sum(n.weight for n in nodes) == pytest.approx(1.0, abs=1e-14)
    with pytest.raises(InputError, match="perforated interval of the producer"):
        interval_nodes(mesh, Perforation("producer", (7.0, 3.0, 40.0), (7.0, 3.0, 60.0)))


@pytest.mark.parametrize("degree", [1, 2])
def test_scene3_jacobian_blocks_match_finite_differences(tmp_path, degree):
    """Every block of the Scene 3 operator (Biot u-pm, thermal strain u-Tm,
    leakoff pm-pf through the tie, the deformable aperture pf-lam and pf-u,
    Tm-pm advection, mu(T), the wells) against central differences, each on
    its own; several steps, the best per block (docs of the Scene 2 test).
    The random rates are those of a step of 1/shift that moved each unknown
    by about its scale (rates of unit size would mean 1e5 scales: the
    increment terms of the fracture's water content, rate x rate / shift,
    then swamp the small pf-Tm block with round-off)."""
    problem = build_problem(tmp_path, "inclined_penny", thm_fe_degree=degree, **COARSE)
    err = jacobian_fd_block_errors(problem, t=1e5, shift=1e-5, eps=(1e-6, 1e-4, 1e-2, 1.0), rate=1e-5)
    print(degree, {f"{a}-{b}": float(f"{v:.2g}") for (a, b), v in err.items()})
    assert set(err) >= COUPLINGS, COUPLINGS - set(err)
    assert max(err.values()) <= 1e-6


def test_scene3_jacobian_check_can_fail(tmp_path, monkeypatch):
    """Negative control: without the Biot block of the flow equation the
    pm-u block is wrong, and the check says so."""
    from petthm.physics.kernels import poroelastic as pe
    full = pe.elastic_terms

    def without_pm_u(el):
        res, jac = full(el)
        return res, [j for j in jac if not (j.test == "pm" and j.trial == "u")]
    monkeypatch.setattr(pe, "elastic_terms", without_pm_u)
    problem = build_problem(tmp_path, "inclined_penny", thm_fe_degree=1, **COARSE)
    err = jacobian_fd_block_errors(problem, t=1e5, shift=1e-5, eps=1e-6, rate=1e-5)   # as above
    assert err[("pm", "u")] > 1e-2
    assert err[("pf", "lam")] <= 1e-6


def _history(path):
    return list(csv.DictReader(open(path / "history.csv")))


def test_scene3_coarse_start(tmp_path, petthm_run):
    """Case 1 on the coarse mesh for 5 days: the initial state is exact
    (lam0 = 40 MPa, a = 0.2 mm), the injector's vertices carry exactly Q,
    the fluid volume and energy balances close at every step, and a = a0 -
    lam/Kn wherever the fracture is closed."""
    out = tmp_path / "run"
    petthm_run("inclined_penny", out, "-thm_fe_degree", 1, "-thm_final_time", 5 * 86400,
               "-thm_dt_growth", 1.0,
               *ARGS)
    rows = _history(out)
    first = rows[0]
    assert float(first["lam_min"]) == pytest.approx(40e6, rel=1e-12)
    assert float(first["aperture_increase_max"]) == 0.0
    for r in rows[1:]:
        assert float(r["injection_rate"]) == pytest.approx(0.005, rel=1e-12)
        assert float(r["production_rate"]) == pytest.approx(0.005, rel=1e-12)
        assert abs(float(r["mass_balance"])) <= 1e-6 and abs(float(r["energy_balance"])) <= 1e-6
        assert float(r["aperture_identity"]) <= 1e-10
    assert float(rows[-1]["aperture_increase_max"]) > 0          # the cooled rock contracts


def test_scene3_layered_mesh_start(tmp_path, petthm_run):
    """The layered mesh (-thm_scene3_layer, issue 16 item 2) for 2 days:
    the initial state is exact, the wells' columns carry exactly Q, the
    balances close, a = a0 - lam/Kn where closed; the first layer is at
    most as thick as asked.  A dip the layered box cannot hold is a one-line error."""
    out = tmp_path / "run"
    petthm_run("inclined_penny", out, "-thm_fe_degree", 1, "-thm_final_time", 2 * 86400,
               "-thm_dt_growth", 1.0, "-thm_scene3_layer", 10, "-thm_scene3_layer_growth", 2, *ARGS)
    rows = _history(out)
    assert float(rows[0]["lam_min"]) == pytest.approx(40e6, rel=1e-12)
    assert len(rows) == 3
    for r in rows[1:]:
        assert float(r["injection_rate"]) == pytest.approx(0.005, rel=1e-12)
        assert float(r["production_rate"]) == pytest.approx(0.005, rel=1e-12)
        assert abs(float(r["mass_balance"])) <= 1e-6 and abs(float(r["energy_balance"])) <= 1e-6
        assert float(r["aperture_identity"]) <= 1e-10
    import meshio
    X = meshio.read(out / "mesh.msh").points
    d = np.abs(X @ np.array([0.5, 0.0, np.sqrt(3.0) / 2]))
    assert 5.0 < np.min(d[d > 1e-9]) <= 10.0 * (1 + 1e-9)   # at most 10 m (a perforation's end may cut it)
    proc, _ = petthm_run("inclined_penny", tmp_path / "steep", "-thm_scene3_layer", 10, "-thm_scene3_dip", 50,
                         *ARGS, check=False)
    assert proc.returncode != 0 and "Traceback" not in proc.stderr
    assert "petthm: error:" in proc.stderr and "-thm_scene3_layer" in proc.stderr
    proc, _ = petthm_run("inclined_penny", tmp_path / "thick", "-thm_scene3_layer", 500, *ARGS, check=False)
    assert proc.returncode != 0 and "Traceback" not in proc.stderr
    assert "petthm: error: option -thm_scene3_layer = 500 m" in proc.stderr


def test_scene3_thin_first_layer_starts(tmp_path, petthm_run):
    """A first layer of 0.22 m (auto at 2 days: 0.5 sqrt(kappa t)) stopped
    Scene 3 at t = 0: the residual's round-off floor (3.7-5.0e-12) lay above
    snes_atol 1e-12 and vinewtonrsls's own test ignores -snes_stol, so Newton
    ran to its limit with updates of x's last bits.  With the step-length
    test (``petthm.solvers.viconvergence``) it runs, and the balances close."""
    out = tmp_path / "run"
    proc, _ = petthm_run("inclined_penny", out, "-thm_fe_degree", 1, "-thm_final_time", 2 * 86400,
                         "-thm_dt_growth", 1.0, "-thm_scene3_layer", "auto", "-thm_scene3_layer_growth", 2,
                         *ARGS)
    assert "0.223 m" in proc.stdout
    rows = _history(out)
    assert len(rows) == 3
    for r in rows[1:]:
        assert abs(float(r["mass_balance"])) <= 1e-6 and abs(float(r["energy_balance"])) <= 1e-6
        assert float(r["aperture_identity"]) <= 1e-10


def test_producer_drawn_below_zero_pressure_stops_cleanly(tmp_path, petthm_run):
    """A production rate the rock cannot give ends the run as failed with a
    message naming the option, never with NaN or a traceback."""
    proc, s = petthm_run("inclined_penny", tmp_path / "run", "-thm_fe_degree", 1,
                         "-thm_final_time", 10 * 86400,
                         "-thm_production_rate", 5.0, *ARGS, check=False)
    assert "Traceback" not in proc.stderr
    assert s["status"] == "failed"
    assert "-thm_production_rate" in s["message"] and "fell to" in s["message"]


@pytest.mark.parametrize("name,opts", [
    ("tight rock km = 1e-18 (the producer cannot give Q: clean stop)", ["-thm_rock_permeability", 1e-18]),
    ("permeable rock km = 1e-12", ["-thm_rock_permeability", 1e-12]),
    ("incompressible Biot limit, first step 60 s", ["-thm_rock_biot_coefficient", 1,
                                                    "-thm_fluid_compressibility", 0, "-thm_rock_porosity", 0,
                                                    "-thm_dt_initial", 60, "-thm_dt_growth", 2]),
    ("stiff joint Kn = 1e13 Pa/m", ["-thm_fracture_normal_stiffness", 1e13]),
])
def test_scene3_stiff_and_extreme_cases(tmp_path, petthm_run, name, opts):
    """Each extreme case on the coarse variant for 3 days: it completes with
    the balances closed and a = a0 - lam/Kn where closed, or (a rock too
    tight for the wells' rates) stops as failed with a message; never NaN."""
    proc, s = petthm_run("inclined_penny", tmp_path / "run", "-thm_fe_degree", 1,
                         "-thm_final_time", 3 * 86400, *ARGS, *opts, check=False)
    assert "Traceback" not in proc.stderr
    rows = _history(tmp_path / "run")
    values = [float(v) for r in rows for k, v in r.items() if k and v not in ("", "nan")]
    assert np.all(np.isfinite(values)), name
    if "clean stop" in name:
        assert s["status"] == "failed" and "-thm_production_rate" in s["message"]
        return
    assert s["status"] == "completed", s["message"]
    for r in rows[1:]:
        assert abs(float(r["mass_balance"])) <= 1e-6 and abs(float(r["energy_balance"])) <= 1e-6, r
        assert float(r["aperture_identity"]) <= 1e-10
