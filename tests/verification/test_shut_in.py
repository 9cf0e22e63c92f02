"""A zero injection rate (-thm_injection_rate 0, which the option's range
allows) is a shut-in: every scene with the option runs quietly to its end
(no numpy warning, no NaN) and its pressure and temperature fields stay at
their initial state within round-off.  A zero rate once gave a zero pressure
scale (x_hat = (x - offset) / 0: NaN from the first step), NaN from the
Lauwerier and leakoff references (divisions by q) and divisions by zero in
the monitors (radial_flow's error over the pressure rise, fracture_inflation's
volume balance over the injected volume); inclined_penny still cooled the
rock at the shut injector (Tm = T_inj on its perforation)."""
import math
import re

import numpy as np
import pytest

from conftest import ROOT, read_csv, run_petthm
from petthm.io.output import read_output

O = f"{ROOT}/options/scenes"
#: coarse meshes, short runs (each about a second here)
SCENES = {
    "lauwerier": ("-options_file", f"{O}/lauwerier.opts", "-thm_mesh_size", 20,
                  "-thm_lauwerier_fracture_size", 5, "-thm_final_time", 1e6),
    "lauwerier_3d": ("-options_file", f"{O}/lauwerier.opts", "-thm_lauwerier_dim", 3, "-thm_mesh_size", 30,
                     "-thm_lauwerier_fracture_size", 10, "-thm_final_time", 1e5),
    "rigid_fracture": ("-options_file", f"{O}/rigid_fracture.opts", "-thm_fe_degree", 1, "-thm_mesh_size", 50,
                       "-thm_scene1_fracture_size", 4, "-thm_rock_permeability", "1e-13",
                       "-thm_final_time", 1e7),
    "leakoff_heat": ("-options_file", f"{O}/leakoff_heat.opts", "-thm_fe_degree", 1, "-thm_mesh_size", 20,
                     "-thm_leakoff_heat_fracture_size", 5, "-thm_final_time", 1e6),
    "radial_flow": ("-options_file", f"{O}/radial_flow.opts", "-thm_fe_degree", 1, "-thm_mesh_size", 50,
                    "-thm_radial_well_size", 5),
    "fracture_inflation": ("-options_file", f"{O}/fracture_inflation.opts", "-thm_fe_degree", 1,
                           "-thm_partial_crack_size", 0.1, "-thm_final_time", 100),
    "penny_impermeable": ("-options_file", f"{O}/penny_impermeable.opts", "-thm_scene2_fracture_size", 40,
                          "-thm_scene2_well_size", 20, "-thm_scene2_layer", 0, "-thm_final_time", 1e5),
    # the producer produces at -thm_production_pressure (= the initial pressure), not at a rate
    "inclined_penny": ("-options_file", f"{O}/inclined_penny_coarse.opts", "-thm_final_time", 2 * 86400,
                       "-thm_dt_growth", 1.0, "-thm_production_rate", 0),
}
#: history columns that are NaN at any rate: not evaluated (frictionless contact; lam_roughness with P1 u)
NOT_EVALUATED = {"slip_max", "slipping_area", "lam_roughness"}
#: NaN or an infinity written as a number (JSON's NaN / Infinity, numpy's nan / inf)
NOT_A_NUMBER = re.compile(r"(?<![a-z_])(nan|inf|infinity)(?![a-z_])", re.IGNORECASE)
PRESSURES, TEMPERATURES = ("pf", "pm"), ("Tf", "Tm")


@pytest.mark.parametrize("case", list(SCENES))
def test_zero_injection_rate_is_a_quiet_shut_in(tmp_path, case):
    scene = case.removesuffix("_3d")
    out = tmp_path / case
    proc, summary = run_petthm(scene, out, *SCENES[case], "-thm_injection_rate", 0)
    text = proc.stdout + proc.stderr
    assert "RuntimeWarning" not in text, text
    assert not NOT_A_NUMBER.search(text), text
    assert summary["status"] == "completed" and summary["exit_code"] == 0, summary
    assert not NOT_A_NUMBER.search((out / "summary.json").read_text())
    for name, value in (summary.get("error") or {}).items():      # the references: finite (or None)
        assert value is None or math.isfinite(value), (name, value)
    for name in ("mass_balance", "energy_balance"):    # at rest: not round-off / round-off (it was 1.0)
        value = (summary.get("balance_max") or {}).get(name)
        assert value is None or value <= 1e-4, (name, value)    # Scene 2's contact: 8.6e-6 of balance.REST
    rows = (read_csv(out / "history.csv"))
    for row in rows:
        bad = {k for k, v in row.items() if k not in NOT_EVALUATED and NOT_A_NUMBER.fullmatch(v.strip())}
        assert not bad, (row["step"], bad)

    checked = []
    for series in ("fields", "fracture"):
        path = out / f"{series}.h5"
        if not path.exists():
            continue
        _, _, t0, start = read_output(str(path), 0)
        _, _, t1, end = read_output(str(path), -1)
        assert t0 == 0.0 and t1 == pytest.approx(summary["final_time"], rel=1e-12) and t1 > 0
        for name in set(start) & set(PRESSURES + TEMPERATURES):
            a, b = np.asarray(start[name], float), np.asarray(end[name], float)
            assert np.ptp(a) == 0.0, (series, name)                # a uniform state at rest ...
            # ... that stays (Pa, degC): round-off of the Newton solve (<= 4e-12 relative seen)
            np.testing.assert_allclose(b, a, rtol=1e-10, atol=0.0, err_msg=f"{series}:{name}")
            checked.append(name)
    assert any(n in checked for n in PRESSURES), checked
    if scene not in ("radial_flow", "fracture_inflation"):          # the scenes with heat
        assert any(n in checked for n in TEMPERATURES), checked
