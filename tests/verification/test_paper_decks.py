"""The paper's scenes as decks (manual: the paper's scenes as decks;
../shared/docs/reservoir.md section 5): a scene's own mesh, whose groups
carry names, run as a deck with options/decks/sceneN.opts gives the scene's
results, compared quantity by quantity through the documented map of the
scene's columns to the deck's."""
import csv

from conftest import ROOT, run_petthm
from petthm.physics.fluid import water_viscosity
from petthm.physics.kernels.wells import well_index

CELSIUS = 273.15


def last_row(outdir) -> dict:
    with open(outdir / "history.csv") as f:
        row = list(csv.DictReader(f))[-1]
    return {k: float(v) if v not in ("", "nan") else float("nan") for k, v in row.items()}


def scene1_side_by_side(outdir, mesh: tuple, *options) -> dict:
    """Scene 1 (rigid_fracture, with the ``mesh`` options) and its deck on
    the scene's own mesh, both with ``options``: {quantity: (scene, deck)} at the end, the deck's
    columns mapped to the scene's:

    * production_temperature = well_well1_temperature;
    * production_rate = -well_well1_rate (the deck's rates are into the rock);
    * injection_pressure (the fracture's pressure at the injector node) =
      well_well0_pressure - Q / PI, the bottom-hole pressure less the
      drawdown of the injector's index PI = 2 T / r_w (T = a^3 / (12 mu(T0)),
      r_w = 0.1 m: the index of a well in a 2D fracture)."""
    _, scene = run_petthm("rigid_fracture", outdir / "scene", "-options_file",
                          f"{ROOT}/options/scenes/rigid_fracture.opts", *mesh, *options)
    _, deck = run_petthm("reservoir", outdir / "deck", "-options_file", f"{ROOT}/options/decks/scene1.opts",
                         "-thm_mesh_file", outdir / "scene" / "mesh.msh", *options)
    assert scene["status"] == deck["status"] == "completed" and scene["steps"] == deck["steps"]
    s, d = last_row(outdir / "scene"), last_row(outdir / "deck")
    iterations = (scene["snes_iterations"], deck["snes_iterations"])
    transmissivity = 1e-3 ** 3 / (12 * water_viscosity(100.0 + CELSIUS))
    drawdown = 1e-4 / well_index(transmissivity, 0.0, 0.1, 1)
    return {"production_temperature": (s["production_temperature"], d["well_well1_temperature"]),
            "production_rate": (s["production_rate"], -d["well_well1_rate"]),
            "injection_pressure": (s["injection_pressure"], d["well_well0_pressure"] - drawdown),
            "Newton iterations": iterations}


def test_scene1_as_a_deck_gives_the_scene_s_results(tmp_path):
    """Scene 1 on a coarse mesh to 1e7 s, P2: the deck's production
    temperature, production rate and injection pressure are the scene's to
    1e-8 (the pressure's change from 1 MPa to 1e-8 of itself), in as many
    Newton iterations within 2 % (the deck's pressure scale is not the
    scene's, so one step may take one more)."""
    coarse = ("-thm_mesh_size", 60, "-thm_scene1_fracture_size", 10, "-thm_scene1_margin", 40)
    pairs = scene1_side_by_side(tmp_path, coarse, "-thm_final_time", 1e7)
    print(pairs)
    for key in ("production_temperature", "production_rate"):
        a, b = pairs[key]
        assert abs(b - a) <= 1e-8 * abs(a), (key, a, b)
    a, b = pairs["injection_pressure"]
    assert abs(b - a) <= 1e-8 * abs(a - 1e6), (a, b)
    a, b = pairs["Newton iterations"]          # the same equations, scaled alike (pf's rows on their own:
    assert b <= 1.02 * a, pairs                 # pf scaled as pm took 10 % more)
