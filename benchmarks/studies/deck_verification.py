"""The decks of tests/verification/test_reservoir.py and
test_deck_fractures.py with their measured errors, printed as the tables
of the manual (user guide, decks: "How well").

    python benchmarks/studies/deck_verification.py [--out DIR]
"""
from __future__ import annotations

import argparse
import os
import pathlib
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "verification")]
import test_deck_fractures as fractured  # noqa: E402
import test_reservoir as decks  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="", help="folder of the runs (default: a temporary one)")
    out = pathlib.Path(ap.parse_args().out or tempfile.mkdtemp(prefix="decks"))
    out.mkdir(parents=True, exist_ok=True)
    os.chdir(ROOT)
    meshes = decks.column_meshes(out)
    rows = []
    for dim, degree in ((2, 1), (2, 2), (3, 1)):
        e = decks.hydrostatic_error(out / f"hydrostatic{dim}d_p{degree}", meshes[dim], dim, degree)
        rows.append((f"hydrostatic column, {dim}D P{degree}", "max abs(p - rho_f g depth) / (rho_f g H)", e))
    ep, eT = decks.flux_errors(out / "flux", meshes[3])
    rows += [("flux and heat flux, 3D P1", "max abs(p - exact) / 1 MPa", ep),
             ("flux and heat flux, 3D P1", "max abs(T - exact) / 30 K", eT)]
    for how in ("normal_stress", "traction"):
        rows.append((f"column loaded at the top by a total {how}, 3D P1", "abs(u_max - exact) / exact",
                     decks.top_load_error(out / f"load_{how}", meshes[3], how)))
    for degree in (1, 2):
        change = decks.at_rest_changes(out / f"rest_p{degree}", meshes[3], degree)
        rows += [(f"deck at rest, P{degree} u", key, change[key])
                 for key in ("u_max", "pm_change_max", "Tm_change_max")]
    for dim in (2, 3):
        error = decks.turned_error(out / f"turned{dim}", dim)
        rows.append((f"turned box, {dim}D", "max abs(p - upright) / drop", error))
    one, two = decks.ranks_changes(out / "ranks", meshes[3])
    for key in ("u_max", "pm_change_max", "Tm_change_max"):
        rows.append(("coupled deck, 2 ranks vs 1", f"{key} relative difference",
                     abs(two[key] - one[key]) / abs(one[key])))
    rows += layered_rows(out, meshes)
    rows += well_rows(out)
    rows += fracture_rows(out)
    print("| deck | measure | measured |\n|---|---|---|")
    for deck, measure, value in rows:
        print(f"| {deck} | {measure} | {value if isinstance(value, str) else f'{value:.2g}'} |")


def layered_rows(out, meshes) -> list:
    """The two layers of different rock (heterogeneous rock)."""
    rows = []
    for dim, degree in ((2, 1), (2, 2), (3, 1)):
        ep, eT = decks.layered_flux_errors(out / f"layers_flux{dim}d_p{degree}", meshes[dim], dim, degree)
        deck = f"two layers, flux and heat flux, {dim}D P{degree}"
        rows += [(deck, "max abs(p - exact) / p_bottom", ep),
                 (deck, "max abs(T - exact) / (T_bottom - T_top)", eT)]
    for dim, degree in ((2, 2), (3, 1), (3, 2)):
        error = decks.layered_load_error(out / f"layers_load{dim}d_p{degree}", meshes[dim], dim, degree)
        rows.append((f"two layers under a top load, {dim}D P{degree}", "max abs(u_z - exact) / abs(u_z top)",
                     error))
    for field, what in (("pm", "water"), ("Tm", "heat")):
        ratio = decks.stored_over_entered(out / f"layers_store_{field}", meshes[2], field)
        rows.append((f"two layers, {what} entering the bottom, 2D P1", "stored / entered - 1", ratio - 1))
    one, two = decks.ranks_changes(out / "layers_ranks", meshes[3], *decks.SANDSTONE, *decks.GRANITE,
                                   *decks.anisotropic(3))
    for key in ("u_max", "pm_change_max", "Tm_change_max"):
        rows.append(("two layers, coupled, 2 ranks vs 1", f"{key} relative difference",
                     abs(two[key] - one[key]) / abs(one[key])))
    return rows


def well_rows(out) -> list:
    """The wells: the water balance of an injector, a schedule, 2 ranks against 1."""
    meshes = decks.well_meshes(out)
    rows = [("injector through two layers, closed box, 3D P1", "stored / injected - 1",
             decks.injected_water_error(out / "well_balance", meshes[3]))]
    one, s = decks.two_wells(out / "wells_one", meshes[2])
    rows.append(("2D injector turning producer at 5e5 s, producer at 1 MPa", "Tm beyond [20, 80] degC (K)",
                 s["bounds"]["Tm"]["violation"]))
    two, _ = decks.two_wells(out / "wells_two", meshes[2], ranks=2)
    for key in ("well_inj_pressure", "well_prod_rate", "well_inj_temperature"):
        a, b = float(one[-1][key]), float(two[-1][key])
        rows.append(("the same, 2 ranks vs 1", f"{key} relative difference", abs(b - a) / abs(a)))
    for h in (50.0, 25.0, 12.5):
        far, well = decks.thiem_errors(out / f"thiem{h:g}", h)
        rows += [(f"well in a disc, h = {h:g} m", "max abs(p - Thiem) / Thiem(r_w), 50 m < r < 450 m", far),
                 (f"well in a disc, h = {h:g} m", "bottom-hole pressure / Thiem(r_w) - 1", well)]
    return rows



def fracture_rows(out) -> list:
    """The fractured decks and the heat that water carries across a boundary."""
    crossing = fractured.layered_deck_box(str(out / "crossing.msh"), [0, -100], [200, 0], 20,
                                          fractures=[("crack", [(0, -50), (200, -50)])])
    rows = []
    for fields in ("pf", "pm,pf"):
        ef, em = fractured.linear_pressure_errors(out / f"linear_{fields.replace(',', '')}", crossing, fields)
        rows.append((f"fracture between held pressures, fields {fields}, 2D P1",
                     "max abs(p - linear) / 1 MPa: pf, pm", f"{ef:.2g}, {em:.2g}"))
        ef, em = fractured.hydrostatic_fracture_errors(out / f"inclined_{fields.replace(',', '')}", fields)
        rows.append((f"inclined fracture under gravity, fields {fields}, 2D P1",
                     "max abs(p - rho_f g depth) / (rho_f g 200 m): pf, pm", f"{ef:.2g}, {em:.2g}"))
    upper, lower, apart = fractured.aperture_differences(out / "apertures")
    rows.append(("two fractures, the lower with its own aperture",
                 "max abs(pf - the deck of one aperture) / 1 MPa: upper, lower; the two apertures' apart",
                 f"{upper:.2g}, {lower:.2g}; {apart:.2g}"))
    for what, value in fractured.fractured_heat_checks(out / "heat", crossing).items():
        rows.append(("cold water through a fracture and the rock (pm, pf, Tm, Tf), 2D P1", what, value))
    lowest, highest, last = fractured.flux_outflow_temperatures(out / "outflow", crossing)
    rows.append(("water drawn out through a flux boundary, its temperature free", "Tm lowest, highest over "
                 "the steps; highest at the end (degC)", f"{lowest:.6g}, {highest:.6g}; {last:.6g}"))
    rows += [("a well crossing two fractures (1 mm, 0.5 mm), closed rock, 3D P1", what, value)
             for what, value in fractured.well_split(out / "split").items()]
    return rows


if __name__ == "__main__":
    main()
