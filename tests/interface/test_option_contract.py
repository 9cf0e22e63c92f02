"""The option names of physics.md section 12 are a contract: every scene to
which -thm_fracture_aperture, -thm_fracture_normal_stiffness,
-thm_insitu_stress, -thm_initial_pressure and -thm_initial_temperature apply
accepts them, and each changes the result as the physics says."""

import numpy as np
import pytest

from conftest import read_csv, run_petthm

PENNY_COARSE = ("-thm_fe_degree", 1, "-thm_scene2_fracture_size", 20, "-thm_scene2_well_size", 10,
                "-thm_scene2_layer", 2, "-thm_scene2_layer_growth", 2.5, "-thm_mesh_size", 150,
                "-thm_final_time", 1e3)
LAUWERIER_COARSE = ("-thm_fe_degree", 1, "-thm_mesh_size", 20, "-thm_lauwerier_fracture_size", 4,
                    "-thm_final_time", 1e3)


def first_row(outdir):
    """The history row of the initial state (step 0)."""
    return {k: float(v) for k, v in read_csv(outdir / "history.csv")[0].items() if v != ""}


def test_contact_patch_takes_the_contract_names(tmp_path):
    """sigma = 45 MPa, p = 10 MPa, Kn = 5e10 Pa/m, a0 = 1 mm: lam = 35 MPa, a = 0.3 mm."""
    _, s = run_petthm("contact_patch", tmp_path, "-thm_contact_dim", 2, "-thm_insitu_stress", 45e6,
                      "-thm_initial_pressure", 10e6, "-thm_fracture_normal_stiffness", 5e10,
                      "-thm_fracture_aperture", 1e-3)
    print(s["lam_exact"], s["aperture_mean"], s["error"])
    assert s["status"] == "completed"
    assert s["lam_exact"] == pytest.approx(35e6, rel=1e-12)
    assert s["aperture_mean"] == pytest.approx(3e-4, rel=1e-9)
    assert s["error"]["lam_error"] <= 1e-9 and s["error"]["aperture_error"] <= 1e-9


def test_insitu_stress_as_a_tensor(tmp_path):
    """Six components: the normal stress on the fracture (normal y in 2D) is
    syy; shear on the fracture plane is refused with a one-line error."""
    _, s = run_petthm("contact_patch", tmp_path / "t", "-thm_contact_dim", 2,
                      "-thm_insitu_stress", "30e6,45e6,30e6,0,0,0", "-thm_initial_pressure", 10e6)
    assert s["lam_exact"] == pytest.approx(35e6, rel=1e-12)
    proc, _ = run_petthm("contact_patch", tmp_path / "s", "-thm_contact_dim", 2,
                         "-thm_insitu_stress", "30e6,45e6,30e6,0,0,2e6", check=False)
    err = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(err) == 1 and "shear" in err[0] and "Traceback" not in proc.stderr
    proc, _ = run_petthm("contact_patch", tmp_path / "n", "-thm_insitu_stress", "1,2,3", check=False)
    assert proc.returncode == 2 and "-thm_insitu_stress" in proc.stderr and "Traceback" not in proc.stderr


def test_sneddon_pressure_and_stress(tmp_path):
    """The opening follows the net pressure p - sigma_n: p = 3 MPa over
    sigma_n = 2 MPa opens as the default 1 MPa over 0; p = 2 MPa over 0 twice as much."""
    opts = ("-thm_sneddon_dim", 2, "-thm_sneddon_crack_size", 0.1)
    w = {}
    for name, extra in (("default", ()), ("shifted", ("-thm_insitu_stress", 2e6, "-thm_initial_pressure",
                                                      3e6)),
                        ("double", ("-thm_initial_pressure", 2e6))):
        _, s = run_petthm("sneddon", tmp_path / name, *opts, *extra)
        w[name] = s["opening_centre"]
    print(w)
    assert w["shifted"] == pytest.approx(w["default"], rel=1e-8)
    assert w["double"] == pytest.approx(2 * w["default"], rel=1e-8)


def test_partial_opening_initial_traction(tmp_path):
    """lam0 = sigma_n - p0 at every crack vertex of the initial state."""
    run_petthm("partial_opening", tmp_path, "-thm_partial_crack_size", 0.1, "-thm_insitu_stress", 9e6,
               "-thm_initial_pressure", 3e6, "-thm_final_time", 0.1)
    assert first_row(tmp_path)["lam_max"] == pytest.approx(6e6, rel=1e-12)


def test_penny_takes_the_contract_names(tmp_path):
    """Scene 2 at t = 0: lam0 = sigma - p0 and a = a0 - lam0/Kn at the
    injector; the produced water has the initial temperature."""
    run_petthm("penny_impermeable", tmp_path, *PENNY_COARSE, "-thm_insitu_stress", 55e6,
               "-thm_initial_pressure", 15e6, "-thm_production_pressure", 15e6,
               "-thm_fracture_aperture", 0.8e-3, "-thm_fracture_normal_stiffness", 2e11,
               "-thm_initial_temperature", 100)
    row = first_row(tmp_path)
    print(row)
    assert row["lam_injector"] == pytest.approx(40e6, rel=1e-12)
    assert row["aperture_injector"] == pytest.approx(0.8e-3 - 40e6 / 2e11, rel=1e-12)
    assert row["production_temperature"] == pytest.approx(100.0, abs=1e-9)
    assert row["injection_pressure"] == pytest.approx(15e6, rel=1e-12)


def test_lauwerier_takes_the_contract_names(tmp_path):
    """Rigid fracture: the pressure drop scales as a0^-3; the initial state
    has p0 and T0."""
    dp = {}
    for name, a in (("a1", 1e-3), ("a2", 2e-3)):
        run_petthm("lauwerier", tmp_path / name, *LAUWERIER_COARSE, "-thm_fracture_aperture", a,
                   "-thm_initial_pressure", 1e6, "-thm_production_pressure", 1e6, "-thm_initial_temperature",
                   90)
        h = (read_csv(tmp_path / name / "history.csv"))
        assert float(h[0]["injection_pressure"]) == pytest.approx(1e6, rel=1e-12)
        assert float(h[0]["production_temperature"]) == pytest.approx(90.0, abs=1e-9)
        dp[name] = float(h[-1]["injection_pressure"]) - 1e6
    print(dp)
    assert dp["a1"] / dp["a2"] == pytest.approx(8.0, rel=0.02)


@pytest.mark.parametrize("scene,opts,column", [
    ("heat_erfc", ("-thm_final_time", 100, "-thm_mesh_size", 0.5), "T_z2"),
    ("thermal_stress", ("-thm_final_time", 100, "-thm_mesh_size", 10), None),
])
def test_initial_temperature(tmp_path, scene, opts, column):
    """The rock starts at -thm_initial_temperature (the reference solutions
    follow it: their error stays small)."""
    _, s = run_petthm(scene, tmp_path, *opts, "-thm_initial_temperature", 120)
    assert s["status"] == "completed"
    if column:
        assert first_row(tmp_path)[column] == pytest.approx(120.0, abs=1e-9)
    params = s["provenance"]["parameters"]
    assert params["-thm_initial_temperature"] == 120.0


def test_no_scene_declares_an_option_twice():
    """Each -thm_ option of every scene is declared once (one type, one help)."""
    from petthm import params
    from petthm.physics import materials
    from petthm.scenes import all_scenes
    scenes = all_scenes()
    for _name, cls in scenes.items():
        params.merged(cls.parameters)                 # raises on a duplicate
    names = [f for cls in scenes.values() for g in cls.parameters for f in g.__dataclass_fields__]
    for contract in ("fracture_aperture", "fracture_normal_stiffness", "insitu_stress", "initial_pressure",
                     "initial_temperature", "rock_permeability", "fluid_viscosity"):
        assert contract in materials.DECLARED and names.count(contract) >= 2, contract
    assert not np.any([n.startswith("joint_") for n in names])


def test_each_scene_loads_from_its_module_alone():
    """scenes.MODULES names the module that defines each scene (a run imports
    only that one): every scene its modules define is in it, with its module,
    and the other way round."""
    import subprocess
    import sys

    from petthm import scenes
    assert {n: c.__module__.rsplit(".", 1)[-1] for n, c in scenes.all_scenes().items()} == scenes.MODULES
    code = ("from petthm import scenes; c = scenes.scene_class('lauwerier'); "
            "import sys; print(c.name, 'petthm.scenes.contact' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "lauwerier False"
