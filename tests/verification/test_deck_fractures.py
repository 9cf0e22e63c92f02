"""Fractures in decks, and the heat that water carries across a deck's
boundaries, each against an exact or independent result (manual: user
guide, decks, "Fractures"; ../shared/docs/reservoir.md)."""
import csv

import numpy as np
import pytest

from conftest import run_petthm
from petthm.io.output import read_output
from petthm.mesh.deckmesh import layered_deck_box

RHO_G = 1000.0 * 9.81            # the default water's rho_f g (Pa/m)
STEADY = ("-thm_dt_initial", 1e5, "-thm_final_time", 1e10, "-thm_dt_max", 1e9)
P1 = ("-thm_fe_degree", 1)


def fracture_values(outdir, name):
    """(node coordinates, values) of a fracture field at the last output."""
    x, _, _, fields = read_output(str(outdir / "fracture.h5"))
    return x, fields[name].ravel()


def rock_values(outdir, name):
    x, _, _, fields = read_output(str(outdir / "fields.h5"))
    return x, fields[name].ravel()


def history(outdir) -> list[dict]:
    with open(outdir / "history.csv") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def crossing(tmp_path_factory):
    """[0, 200] x [-100, 0] cut by a fracture 'crack' along y = -50 from the west face to the east face."""
    return layered_deck_box(str(tmp_path_factory.mktemp("fdeck") / "crossing.msh"), [0, -100], [200, 0], 20,
                            fractures=[("crack", [(0, -50), (200, -50)])])


def linear_pressure_errors(outdir, mesh, fields) -> tuple[float, float]:
    """The west face held at 1 MPa, the east at 0: in steady state the
    pressure falls linearly along the fracture (and, with a permeable rock,
    in the rock around it: the flow is parallel to the fracture), which P1
    holds exactly.  The largest errors of pf and pm (0 without pm) over 1 MPa."""
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fractures", "crack",
                      "-thm_fields", fields, "-thm_rock_permeability", 1e-15, "-thm_bc_west_pressure", 1e6,
                      "-thm_bc_east_pressure", 0, *P1, *STEADY)
    assert s["status"] == "completed"

    def error(x, p):
        return float(np.max(np.abs(p - 1e6 * (1 - x[:, 0] / 200)))) / 1e6
    return error(*fracture_values(outdir, "pf")), error(*rock_values(outdir, "pm")) if "pm" in fields else 0.0


@pytest.mark.parametrize("fields", ["pf", "pm,pf"])
def test_a_fracture_between_two_held_pressures_carries_the_exact_linear_pressure(tmp_path, crossing, fields):
    ef, em = linear_pressure_errors(tmp_path, crossing, fields)
    assert ef < 1e-9 and em < 1e-9, (ef, em)


def hydrostatic_fracture_errors(outdir, fields) -> tuple[float, float]:
    """A fracture from (50, -150) up to the top face, the top held at p = 0,
    under gravity: the pressure along it (and in the rock) becomes rho_f g
    depth, exactly for P1 (rho_f g acts along the fracture only).  The
    largest errors of pf and pm (0 without pm) over rho_f g 200 m."""
    outdir.mkdir(parents=True, exist_ok=True)
    mesh = layered_deck_box(str(outdir / "inclined.msh"), [0, -200], [200, 0], 25,
                            fractures=[("slant", [(50, -150), (150, 0)])])
    _, s = run_petthm("reservoir", outdir / "run", "-thm_mesh_file", mesh, "-thm_fractures", "slant",
                      "-thm_fields", fields, "-thm_rock_permeability", 1e-15, "-thm_gravity", 9.81,
                      "-thm_bc_top_pressure", 0, *P1, *STEADY)
    assert s["status"] == "completed"

    def error(x, p):
        return float(np.max(np.abs(p - RHO_G * -x[:, 1]))) / (RHO_G * 200)
    return (error(*fracture_values(outdir / "run", "pf")),
            error(*rock_values(outdir / "run", "pm")) if "pm" in fields else 0.0)


@pytest.mark.parametrize("fields", ["pf", "pm,pf"])
def test_water_in_an_inclined_fracture_under_gravity_becomes_hydrostatic(tmp_path, fields):
    ef, em = hydrostatic_fracture_errors(tmp_path, fields)
    assert ef < 1e-9 and em < 1e-9, (ef, em)


def two_fracture_pressures(outdir, mesh, *apertures) -> dict:
    """{y: pf along the fracture at y} after 0.02 s of water entering two
    fractures of impermeable rock from the west face held at 1 MPa (the
    pressure diffuses along a fracture with a^2 / (12 mu c_f), 1.9e5 m2/s
    at a = 1 mm: some 60 m in that time)."""
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fractures", "upper,lower",
                      "-thm_fields", "pf", "-thm_bc_west_pressure", 1e6, *P1, *apertures,
                      "-thm_dt_initial", 0.002, "-thm_dt_growth", 1, "-thm_final_time", 0.02)
    assert s["status"] == "completed"
    x, pf = fracture_values(outdir, "pf")
    out = {}
    for y in (-30.0, -70.0):
        on = np.isclose(x[:, 1], y)
        order = np.argsort(x[on, 0])
        out[y] = pf[on][order]
    return out


def aperture_differences(outdir) -> tuple[float, float, float]:
    """Two fractures of one deck, the lower one with its own aperture
    (-thm_fracture_lower_aperture): (upper against the deck with its
    aperture on both, lower against the deck with its aperture on both,
    the lower fracture of those two decks against each other), the largest
    differences of pf over 1 MPa."""
    outdir.mkdir(parents=True, exist_ok=True)
    mesh = layered_deck_box(str(outdir / "two.msh"), [0, -100], [200, 0], 20,
                            fractures=[("upper", [(0, -30), (150, -30)]), ("lower", [(0, -70), (150, -70)])])
    wide = two_fracture_pressures(outdir / "wide", mesh, "-thm_fracture_aperture", 1e-3)
    narrow = two_fracture_pressures(outdir / "narrow", mesh, "-thm_fracture_aperture", 4e-4)
    each = two_fracture_pressures(outdir / "each", mesh, "-thm_fracture_aperture", 1e-3,
                                  "-thm_fracture_lower_aperture", 4e-4)
    return tuple(float(np.max(np.abs(a - b))) / 1e6 for a, b in
                 ((each[-30.0], wide[-30.0]), (each[-70.0], narrow[-70.0]), (wide[-70.0], narrow[-70.0])))


def test_each_fracture_takes_its_own_aperture(tmp_path):
    """Each fracture fills as the same deck with its aperture on both, to
    round-off; the two apertures differ by far more."""
    upper, lower, apart = aperture_differences(tmp_path)
    assert upper < 1e-12 and lower < 1e-12 and apart > 1e-2, (upper, lower, apart)


def fractured_heat(outdir, mesh, ranks=1) -> dict:
    """Water at 20 degC driven through the fracture and the rock at 80 degC
    between the west face (1 MPa, 20 degC) and the east face (0, 80 degC)."""
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fractures", "crack",
                      "-thm_fields", "pm,pf,Tm,Tf", "-thm_rock_permeability", 1e-15,
                      "-thm_initial_temperature", 80, "-thm_initial_pressure", "1e6*(1-x/200)",
                      "-thm_bc_west_pressure", 1e6, "-thm_bc_west_temperature", 20,
                      "-thm_bc_east_pressure", 0, "-thm_bc_east_temperature", 80, *P1,
                      "-thm_dt_initial", 1e5, "-thm_final_time", 3e7, ranks=ranks)
    assert s["status"] == "completed"
    return s


def fractured_heat_checks(outdir, mesh) -> dict:
    """{what: value} of the cold-water deck on one rank and two: how far Tf
    and Tm leave [20, 80] degC over the steps (K), Tf at mid-length at the
    end (degC), and the largest difference of the changes written
    (summary.json) on two ranks against one, over the pressure drop (1 MPa),
    the temperature range (60 K) or the aperture."""
    one = fractured_heat(outdir / "one", mesh)
    rows = history(outdir / "one")
    out = {f"{name} beyond [20, 80] degC (K)": max(0.0, 20 - min(float(r[f"{name}_min"]) for r in rows),
                                                  max(float(r[f"{name}_max"]) for r in rows) - 80)
           for name in ("Tf", "Tm")}
    x, Tf = fracture_values(outdir / "one", "Tf")
    out["Tf at mid-length (degC)"] = float(Tf[np.argmin(np.abs(x[:, 0] - 100))])
    two = fractured_heat(outdir / "two", mesh, ranks=2)
    scale = {"p": 1e6, "T": 60.0, "f": 1e-3}        # the pressure drop, the temperature range, the aperture
    out["2 ranks vs 1, largest difference of the changes written, over their scale"] = max(
        abs(two["change"][k] - v) / scale[k[0]] for k, v in one["change"].items())
    return out


def test_cold_water_through_a_fracture_stays_within_its_temperatures_on_one_rank_and_two(tmp_path,
                                                                                         crossing):
    """The fracture's water and the rock stay within [20, 80] degC at every
    step (to 1e-3 of the range), the front has passed mid-length, and two
    ranks give one rank's run."""
    c = fractured_heat_checks(tmp_path, crossing)
    assert c["Tf beyond [20, 80] degC (K)"] < 0.06 and c["Tm beyond [20, 80] degC (K)"] < 0.06, c
    assert c["Tf at mid-length (degC)"] < 50, c
    assert c["2 ranks vs 1, largest difference of the changes written, over their scale"] < 1e-10, c


def flux_outflow_temperatures(outdir, mesh) -> tuple[float, float, float]:
    """Water drawn out through the east face (a flux of 1e-6 m/s, its
    temperature free) and replaced at 20 degC through the west face: the
    lowest and highest Tm over the steps and the highest at the end (degC)."""
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fields", "pm,Tm",
                      "-thm_rock_permeability", 1e-11, "-thm_initial_temperature", 80,
                      "-thm_bc_west_pressure", 0, "-thm_bc_west_temperature", 20, "-thm_bc_east_flux", 1e-6,
                      *P1, "-thm_dt_initial", 1e5, "-thm_final_time", 3e8)
    assert s["status"] == "completed"
    rows = history(outdir)
    return (min(float(r["Tm_min"]) for r in rows), max(float(r["Tm_max"]) for r in rows),
            float(rows[-1]["Tm_max"]))


def test_water_leaving_through_a_flux_boundary_takes_its_heat(tmp_path, crossing):
    """The water leaving takes its heat with it, so the rock cools from
    80 degC to 20 degC and never leaves [20, 80] (without the outflow's heat
    the east nodes would gather the heat of all the water that passes)."""
    lowest, highest, last = flux_outflow_temperatures(tmp_path, crossing)
    assert lowest > 20 - 0.06 and highest < 80 + 0.06 and last < 20.01, (lowest, highest, last)


def test_the_jacobian_of_a_fractured_deck_matches_finite_differences(tmp_path):
    """Two fractures of their own apertures in a permeable rock under
    gravity, mu(T), leakoff, the walls tied, a flux boundary carrying its
    water's heat: the whole Jacobian against central differences.  Negative
    control: the carried heat's own derivative left out fails."""
    import dataclasses

    from conftest import build_problem
    from petthm.discretisation.model import MATRIX
    from petthm.verification.jacobian import jacobian_fd_block_errors
    mesh = layered_deck_box(str(tmp_path / "two.msh"), [0, -100], [200, 0], 25,
                            fractures=[("upper", [(0, -30), (150, -30)]), ("lower", [(50, -70), (200, -80)])])
    problem = build_problem(tmp_path / "run", "reservoir", thm_mesh_file=mesh, thm_fractures="upper,lower",
                            thm_fields="pm,pf,Tm,Tf", thm_fe_degree=1, thm_rock_permeability="1e-13",
                            thm_fluid_viscosity="water", thm_gravity=9.81, thm_fracture_lower_aperture=4e-4,
                            thm_initial_temperature=60, thm_initial_pressure="1e6+(-y)*9810",
                            thm_bc_west_pressure="1e6+(-y)*9810", thm_bc_west_temperature=20,
                            thm_bc_east_flux=1e-7)
    assert problem.model.fracture_regions is not None
    errs = jacobian_fd_block_errors(problem, t=1e5, shift=1e-4, eps=1e-6, rate=1e-4)
    print({k: f"{v:.1e}" for k, v in errs.items()})
    assert max(errs.values()) < 1e-6, errs
    asm = problem.region(MATRIX)
    k = next(i for i, ft in enumerate(asm.model.facets) if ft.field == "Tm")
    asm.model.facets[k] = dataclasses.replace(asm.model.facets[k],
                                              g0=lambda ctx: 0.0 * ctx.value("Tm")[..., None])
    asm.build_pattern()
    problem.J = None
    errs = jacobian_fd_block_errors(problem, t=1e5, shift=1e-4, eps=1e-6, rate=1e-4)
    assert max(errs.values()) > 1e-4, errs


def crossing_rates(outdir, mesh, *options, ranks=1) -> dict:
    """{column: value} of the last row of a vertical well crossing the
    fractures 'upper' and 'lower' of a box of (nearly) impermeable rock
    whose sides are held at p = 0 (flow only), in steady state."""
    sides = [a for face in ("west", "east", "south", "north") for a in (f"-thm_bc_{face}_pressure", 0)]
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fractures", "upper,lower",
                      "-thm_fields", "pm,pf", "-thm_rock_permeability", 1e-22, "-thm_wells", "inj", *sides,
                      *P1, *options, "-thm_dt_initial", 1, "-thm_final_time", 1000, ranks=ranks)
    assert s["status"] == "completed"
    return {k: float(v) for k, v in history(outdir)[-1].items() if k.startswith("well_")}


def well_split(outdir) -> dict:
    """A well held at 1 MPa crossing two fractures of 1 mm (A), and of 1 mm
    above 0.5 mm (C); C under rate control at 0.1 m3/s (R), on 1 and 2 ranks.
    With the rock closed, each fracture takes a rate proportional to its
    transmissivity a^3 / (12 mu) (its flow and its well index both are):
    C's upper fracture takes A's, its lower one (1/2)^3 of A's; R splits
    0.1 m3/s in C's proportions."""
    outdir.mkdir(parents=True, exist_ok=True)

    def square(z):
        return [(0, 0, z), (200, 0, z), (200, 200, z), (0, 200, z)]
    mesh = layered_deck_box(str(outdir / "crossed.msh"), [0, 0, -200], [200, 200, 0], 40,
                            wells=[("inj", [(100, 100, -180), (100, 100, -20)])],
                            fractures=[("upper", square(-60)), ("lower", square(-140))])
    A = crossing_rates(outdir / "A", mesh, "-thm_well_inj_pressure", 1e6)
    C = crossing_rates(outdir / "C", mesh, "-thm_well_inj_pressure", 1e6,
                       "-thm_fracture_lower_aperture", 5e-4)
    R = crossing_rates(outdir / "R", mesh, "-thm_well_inj_rate", 0.1, "-thm_fracture_lower_aperture", 5e-4)
    R2 = crossing_rates(outdir / "R2", mesh, "-thm_well_inj_rate", 0.1, "-thm_fracture_lower_aperture", 5e-4,
                        ranks=2)
    up, low = "well_inj_fracture_upper_rate", "well_inj_fracture_lower_rate"
    return {"upper: C / A - 1": C[up] / A[up] - 1,
            "lower: C / A / (1/2)^3 - 1": C[low] / A[low] * 8 - 1,
            "rate control: (upper + lower) / 0.1 - 1": (R[up] + R[low]) / 0.1 - 1,
            "rate control: upper / lower over C's - 1": (R[up] / R[low]) / (C[up] / C[low]) - 1,
            "2 ranks against 1: the rates' largest relative difference":
                max(abs(R2[k] - R[k]) / abs(R[k]) for k in (up, low, "well_inj_pressure"))}


def test_a_well_crossing_two_fractures_splits_its_rate_by_their_transmissivities(tmp_path):
    split = well_split(tmp_path)
    print(split)
    assert all(abs(v) < 1e-6 for v in split.values()), split
