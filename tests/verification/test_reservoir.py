"""The reservoir scene: decks on gmsh meshes with named groups, each against
an exact result (manual: user guide, decks; ../shared/docs/reservoir.md)."""
import numpy as np
import pytest

from conftest import run_petthm
from petthm.io.output import read_output
from petthm.mesh.deckmesh import layered_deck_box

RHO_G = 1000.0 * 9.81            # the default water's rho_f g (Pa/m)


def column_meshes(folder) -> dict:
    """2D and 3D columns 1000 m deep of two named layers (granite below, sandstone above)."""
    layers = [("granite", -500.0), ("sandstone", 0.0)]
    return {2: layered_deck_box(str(folder / "col2.msh"), [0, -1000], [200, 0], 125, layers),
            3: layered_deck_box(str(folder / "col3.msh"), [0, 0, -1000], [200, 200, 0], 250, layers)}


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    return column_meshes(tmp_path_factory.mktemp("decks"))


def final(outdir, name):
    """(node coordinates, values) of a field at the last output (its own degree's nodes)."""
    x, _, _, fields = read_output(str(outdir / "fields.h5"))
    return x, fields[name]


STEADY = ("-thm_dt_initial", 1e8, "-thm_final_time", 2e9, "-thm_dt_max", 1e9)
HOLD = tuple(a for face in ("bottom", "west", "east", "south", "north")
             for a in (f"-thm_bc_{face}_normal_displacement", 0))


def hydrostatic_error(outdir, mesh, dim, degree) -> float:
    """From p0 = 0 with the top held at 0, under gravity: the largest
    |p - rho_f g depth| at the end, relative to rho_f g H (H = 1000 m)."""
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fields", "pm", "-thm_gravity", 9.81,
                      "-thm_fe_degree", degree, "-thm_bc_top_pressure", 0, *STEADY)
    assert s["status"] == "completed"
    x, p = final(outdir, "pm")
    return float(np.max(np.abs(p.ravel() - RHO_G * -x[:, dim - 1]))) / (RHO_G * 1000)


def steady_fluxes(outdir, mesh, *rock) -> tuple:
    """(x, p, T) at the end of a pm, Tm deck of ``rock`` whose bottom takes
    water at 1e-8 m/s and heat at 0.09 W/m2, its top held at p = 0 and
    20 degC, run to steady state (the water's heat capacity made negligible)."""
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fields", "pm,Tm", *rock,
                      "-thm_fluid_heat_capacity", 1e-9,
                      "-thm_bc_top_pressure", 0, "-thm_bc_bottom_flux", -1e-8, "-thm_initial_temperature", 20,
                      "-thm_bc_top_temperature", 20, "-thm_bc_bottom_heat_flux", -0.09, *STEADY,
                      "-thm_final_time", 1e14, "-thm_dt_max", 1e13)
    assert s["status"] == "completed"
    x, p = final(outdir, "pm")
    return x, p, final(outdir, "Tm")[1]


def flux_errors(outdir, mesh) -> tuple[float, float]:
    """No gravity: water enters through the bottom at 1e-8 m/s (an outward
    flux of -1e-8) with the top at p = 0, so p = -1e3 z (k = 1e-14, mu =
    1e-3); heat enters at 0.09 W/m2 with the top at 20 degC, so T = 20 -
    0.09 z / 3 (the water's heat capacity made negligible): the largest
    errors relative to 1 MPa and 30 K."""
    x, p, T = steady_fluxes(outdir, mesh, "-thm_rock_conductivity", 3.0, "-thm_fluid_conductivity", 3.0)
    return (float(np.max(np.abs(p.ravel() - (-1e3 * x[:, 2])))) / 1e6,
            float(np.max(np.abs(T.ravel() - (20 - 0.03 * x[:, 2])))) / 30)


def at_rest_options(mesh, stress):
    """Hydrostatic water, a geotherm between held temperatures and
    ``stress`` times the lithostatic stress, under gravity."""
    rho_b = 0.95 * 2650 + 0.05 * 1000
    s = f"(-z)*{stress * rho_b * 9.81!r}"
    return ("-thm_mesh_file", mesh, "-thm_gravity", 9.81, "-thm_rock_porosity", 0.05,
            "-thm_initial_pressure", f"(-z)*{RHO_G!r}", "-thm_initial_temperature", "20+(-z)*0.03",
            "-thm_insitu_stress", f"{s},{s},{s},0,0,0",
            "-thm_bc_top_temperature", 20, "-thm_bc_bottom_temperature", 50, "-thm_bc_top_pressure", 0,
            *HOLD, "-thm_final_time", 3e8)


def at_rest_changes(outdir, mesh, degree) -> dict:
    _, s = run_petthm("reservoir", outdir, *at_rest_options(mesh, 1.0), "-thm_fe_degree", degree)
    assert s["status"] == "completed"
    return s["change"]


def turned_error(outdir, dim) -> float:
    """An anisotropic permeability: the box turned by 30 degrees with its
    tensor turned alike (off-diagonal terms) against the upright box's
    linear pressure between its west and east faces, relative to the drop."""
    k = np.diag([4e-14, 1e-14, 2e-14][:dim])
    c, s_ = np.cos(np.radians(30)), np.sin(np.radians(30))
    R = np.eye(dim)
    R[:2, :2] = [[c, -s_], [s_, c]]
    K = R @ k @ R.T
    parts = (K[0, 0], K[1, 1], K[2, 2], K[1, 2], K[0, 2], K[0, 1]) if dim == 3 else \
        (K[0, 0], K[1, 1], K[0, 1])
    outdir.mkdir(parents=True, exist_ok=True)
    mesh = layered_deck_box(str(outdir / "turned.msh"), [0.0] * dim, [300.0, 200.0, 100.0][:dim], 60.0,
                            rotation=30.0)
    _, s = run_petthm("reservoir", outdir / "run", "-thm_mesh_file", mesh, "-thm_fields", "pm",
                      "-thm_rock_permeability", ",".join(f"{v!r}" for v in parts),
                      "-thm_bc_west_pressure", 3e6, "-thm_bc_east_pressure", 0, *STEADY)
    assert s["status"] == "completed"
    x, p = final(outdir / "run", "pm")
    upright = x @ R                       # the turned points turned back
    return float(np.max(np.abs(p.ravel() - 3e6 * (1 - upright[:, 0] / 300.0)))) / 3e6


def ranks_changes(outdir, mesh, *rock) -> tuple[dict, dict]:
    """A coupled deck (u, pm, Tm) cooled from the top, on 1 and 2 ranks
    (``rock``: options of its rock)."""
    opts = ("-thm_mesh_file", mesh, "-thm_initial_temperature", 80, "-thm_bc_top_temperature", 20,
            "-thm_bc_top_pressure", 0, "-thm_rock_porosity", 0.1, "-thm_final_time", 3e7, *HOLD, *rock)
    _, s1 = run_petthm("reservoir", outdir / "one", *opts)
    _, s2 = run_petthm("reservoir", outdir / "two", *opts, ranks=2)
    return s1["change"], s2["change"]


@pytest.mark.parametrize("dim,degree", [(2, 1), (2, 2), (3, 1)])
def test_pressure_under_gravity_becomes_hydrostatic(tmp_path, meshes, dim, degree):
    """p = rho_f g depth is linear, so exact for P1 and P2 in steady state:
    the flow law carries rho_f g (without it p would stay 0)."""
    assert hydrostatic_error(tmp_path, meshes[dim], dim, degree) < 1e-8


def test_a_flux_and_a_heat_flux_drive_the_exact_linear_profiles(tmp_path, meshes):
    ep, eT = flux_errors(tmp_path, meshes[3])
    assert ep < 1e-6 and eT < 1e-6


@pytest.mark.parametrize("degree", [1, 2])
def test_a_deck_in_equilibrium_stays_at_rest(tmp_path, meshes, degree):
    """Nothing moves, to round-off (the refusal below is the negative control)."""
    change = at_rest_changes(tmp_path, meshes[3], degree)
    assert change["u_max"] < 1e-12
    assert change["pm_change_max"] < 1e-12 * RHO_G * 1000
    assert change["Tm_change_max"] < 1e-12 * 30


def test_a_stress_that_does_not_balance_gravity_is_refused(tmp_path, meshes):
    proc, _ = run_petthm("reservoir", tmp_path, *at_rest_options(meshes[3], 1.01), check=False)
    msg = proc.stderr.strip().splitlines()[-1]
    assert msg.startswith("petthm: error: option -thm_insitu_stress") and "0.01 times rho_b g" in msg
    assert "region" in msg and "-thm_equilibrium_tolerance" in msg


@pytest.mark.parametrize("dim", [2, 3])
def test_a_turned_deck_with_the_turned_permeability_equals_the_upright_one(tmp_path, dim):
    assert turned_error(tmp_path, dim) < 1e-8


def test_one_rank_equals_two(tmp_path, meshes):
    one, two = ranks_changes(tmp_path, meshes[3])
    for key in ("u_max", "pm_change_max", "Tm_change_max"):
        assert two[key] == pytest.approx(one[key], rel=1e-8), key


def top_load_error(outdir, mesh, how: str) -> float:
    """A column under an isotropic in-situ stress of 20 MPa (no gravity),
    on rollers, its top loaded to 21 MPa total (``how``: normal_stress, or
    the traction 0,0,-21e6), its bottom held by ``_displacement 0,0,0``:
    uniaxial strain, so the top settles by 1 MPa H / (lambda + 2G), which P1
    holds exactly (the displacement is linear).  The largest displacement's
    error relative to it."""
    load = ("-thm_bc_top_normal_stress", 21e6) if how == "normal_stress" else \
        ("-thm_bc_top_traction", "0,0,-21e6")
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fields", "u", "-thm_fe_degree", 1,
                      "-thm_insitu_stress", 20e6, *load, "-thm_bc_bottom_displacement", "0,0,0",
                      *[a for face in ("west", "east", "south", "north")
                        for a in (f"-thm_bc_{face}_normal_displacement", 0)],
                      "-thm_dt_initial", 1, "-thm_final_time", 1)
    assert s["status"] == "completed"
    E, nu = 37.5e9, 0.25                 # the default rock
    constrained = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    exact = 1e6 * 1000 / constrained
    return abs(s["change"]["u_max"] - exact) / exact


@pytest.mark.parametrize("how", ["normal_stress", "traction"])
def test_a_total_load_on_the_top_settles_the_column_by_its_excess(tmp_path, meshes, how):
    """The loads are totals: the in-situ traction is taken off (without
    that the column would settle by 21 MPa H / M, 21 times too far)."""
    assert top_load_error(tmp_path, meshes[3], how) < 1e-10


@pytest.mark.parametrize("option,flow_file", [((), "fields_p1.h5"),
                                              (("-thm_fe_degree_flow", 2), "fields.h5")])
def test_the_flow_degree_is_p1_beside_p2_u_unless_set(tmp_path, meshes, option, flow_file):
    """Taylor-Hood by default (P2 u, P1 pm and Tm: written with the P1
    fields); -thm_fe_degree_flow 2 gives P2 pm and Tm (with u's)."""
    _, s = run_petthm("reservoir", tmp_path, *at_rest_options(meshes[3], 1.0), "-thm_fe_degree", 2, *option,
                      "-ts_max_steps", 1, "-thm_heat_transport", "supg", check=False)
    assert s["status"] == "stopped"
    fields = read_output(str(tmp_path / flow_file))[3]
    assert "pm" in fields and "Tm" in fields and ("u" in fields) == (flow_file == "fields.h5")


# -- heterogeneous rock ---------------------------------------------------------------------------
#: the lower layer's rock, where it differs from the upper's (the global values)
GRANITE = ("-thm_region_granite_rock_permeability", "1e-15", "-thm_region_granite_rock_conductivity", 1.5,
           "-thm_region_granite_rock_youngs_modulus", 60e9, "-thm_region_granite_rock_poisson_ratio", 0.2,
           "-thm_region_granite_rock_porosity", 0.01, "-thm_region_granite_rock_biot_coefficient", 0.5,
           "-thm_region_granite_rock_density", 2700, "-thm_region_granite_rock_heat_capacity", 900)
#: the upper layer: softer, more porous
SANDSTONE = ("-thm_rock_conductivity", 3.0, "-thm_rock_youngs_modulus", 20e9, "-thm_rock_poisson_ratio", 0.3,
             "-thm_rock_porosity", 0.2, "-thm_rock_biot_coefficient", 0.9, "-thm_rock_density", 2400,
             "-thm_rock_heat_capacity", 800)


def anisotropic(dim) -> tuple:
    """The upper layer's permeability: the vertical a fifth of the horizontal."""
    return ("-thm_rock_permeability", "1e-14,1e-14,2e-15" if dim == 3 else "1e-14,2e-15")


def layered_flux_errors(outdir, mesh, dim, degree) -> tuple[float, float]:
    """Water enters through the bottom at 1e-8 m/s and heat at 0.09 W/m2,
    the top held at p = 0 and 20 degC: in steady state each layer carries
    the same flux, so p and T are linear in each layer with slopes
    q mu / k_zz and q_h / lambda of its own rock (water's heat capacity made
    negligible, no porosity so that lambda is the rock's); the largest errors
    relative to the pressure and temperature at the bottom."""
    x, p, T = steady_fluxes(outdir, mesh, *SANDSTONE, *GRANITE, *anisotropic(dim), "-thm_rock_porosity", 0,
                            "-thm_region_granite_rock_porosity", 0, "-thm_fe_degree", degree)
    depth = -x[:, dim - 1]
    kzz = 2e-15                                        # the sandstone's vertical permeability
    upper, lower = np.minimum(depth, 500.0), np.maximum(depth - 500.0, 0.0)
    p_exact = 1e-8 * 1e-3 * (upper / kzz + lower / 1e-15)
    T_exact = 20 + 0.09 * (upper / 3.0 + lower / 1.5)
    return (float(np.max(np.abs(p.ravel() - p_exact)) / p_exact.max()),
            float(np.max(np.abs(T.ravel() - T_exact)) / (T_exact.max() - 20)))


def layered_load_error(outdir, mesh, dim, degree) -> float:
    """The two layers on rollers under a total normal stress of 10 MPa on
    the top (no in-situ stress): uniaxial strain, each layer shortened by
    10 MPa / M of its own rock (M = E (1 - nu) / ((1 + nu) (1 - 2 nu))), so
    u_z is linear in each layer; its largest error relative to the top's."""
    rollers = [a for face in ("bottom", "west", "east", "south", "north")[:2 * dim - 1]
               for a in (f"-thm_bc_{face}_normal_displacement", 0)]
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fields", "u", *SANDSTONE, *GRANITE,
                      "-thm_fe_degree", degree, "-thm_bc_top_normal_stress", 1e7, *rollers,
                      "-thm_dt_initial", 1, "-thm_final_time", 1)
    assert s["status"] == "completed"
    x, u = final(outdir, "u")

    def constrained(E, nu):
        return E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    height = x[:, dim - 1] + 1000.0
    exact = -1e7 * (np.minimum(height, 500.0) / constrained(60e9, 0.2) +
                    np.maximum(height - 500.0, 0.0) / constrained(20e9, 0.3))
    return float(np.max(np.abs(u[:, dim - 1] - exact)) / np.abs(exact).max())


@pytest.mark.parametrize("dim,degree", [(2, 1), (2, 2), (3, 1)])
def test_layers_of_different_rock_carry_one_flux_with_their_own_gradients(tmp_path, meshes, dim, degree):
    """Flux continuity across the region boundary: the piecewise-linear
    profiles are exact (nodes on the boundary) for P1 and P2."""
    ep, eT = layered_flux_errors(tmp_path, meshes[dim], dim, degree)
    assert ep < 1e-8 and eT < 1e-8


@pytest.mark.parametrize("dim,degree", [(2, 2), (3, 1), (3, 2)])
def test_layers_of_different_stiffness_shorten_each_by_its_own_modulus(tmp_path, meshes, dim, degree):
    assert layered_load_error(tmp_path, meshes[dim], dim, degree) < 1e-10


def stored_over_entered(outdir, mesh, field, uniform=False) -> float:
    """Water (``pm``) or heat (``Tm``) enters through the bottom of the 2D
    column, which holds it all (no other boundary condition): the amount
    each region stores, int S (p - p0) or int C (T - T0) with its own S or
    C (``uniform``: the upper layer's everywhere, the negative control),
    summed from the written P1 fields and the written region of each
    cell, over the amount that entered: 1 to the solver's tolerance."""
    from petthm.io.output import read_cell_regions
    flux = {"pm": ("-thm_bc_bottom_flux", -1e-8), "Tm": ("-thm_bc_bottom_heat_flux", -0.09)}[field]
    t_end = 1e7
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fields", field, *SANDSTONE, *GRANITE,
                      "-thm_fe_degree", 1, "-thm_initial_temperature", 20, *flux,
                      "-thm_dt_initial", 1e6, "-thm_final_time", t_end)
    assert s["status"] == "completed"
    x, cells, t, fields = read_output(str(outdir / "fields.h5"))
    tags = read_cell_regions(str(outdir))
    granite = tags == min(tags)                        # the lower layer's group was made first
    change = fields[field].ravel() - (0.0 if field == "pm" else 20.0)          # Tm is written in degC
    corners = x[cells]
    area = 0.5 * np.abs(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]))
    mean = change[cells].mean(axis=1)

    def coefficient(phi, alpha, E, nu, rho, c):
        if field == "Tm":
            return (1 - phi) * rho * c + phi * 1000.0 * 4200.0
        bulk = E / (3 * (1 - 2 * nu))
        return phi * 4.5e-10 + (alpha - phi) * (1 - alpha) / bulk
    upper = coefficient(0.2, 0.9, 20e9, 0.3, 2400, 800)
    lower = upper if uniform else coefficient(0.01, 0.5, 60e9, 0.2, 2700, 900)
    stored = float(np.sum(np.where(granite, lower, upper) * area * mean))
    return stored / (abs(flux[1]) * 200.0 * t)


@pytest.mark.parametrize("field", ["pm", "Tm"])
def test_each_region_stores_with_its_own_storage_and_capacity(tmp_path, meshes, field):
    assert stored_over_entered(tmp_path, meshes[2], field) == pytest.approx(1.0, abs=1e-8)
    assert abs(stored_over_entered(tmp_path / "control", meshes[2], field, uniform=True) - 1.0) > 1e-2


def test_one_rank_equals_two_on_layers_of_different_rock(tmp_path, meshes):
    one, two = ranks_changes(tmp_path, meshes[3], *SANDSTONE, *GRANITE, *anisotropic(3))
    for key in ("u_max", "pm_change_max", "Tm_change_max"):
        assert two[key] == pytest.approx(one[key], rel=1e-8), key


# -- wells ----------------------------------------------------------------------------------------
def well_meshes(folder) -> dict:
    """The two layers with a vertical well through both (3D), and a 2D section with two point wells."""
    layers = [("granite", -200.0), ("sandstone", 0.0)]
    return {3: layered_deck_box(str(folder / "well3.msh"), [0, 0, -400], [400, 400, 0], 100, layers,
                                wells=[("inj", [(200, 200, -350), (200, 200, -50)])]),
            2: layered_deck_box(str(folder / "well2.msh"), [0, -400], [400, 0], 20, layers,
                                wells=[("inj", [(200, -100)]), ("prod", [(350, -300)])])}


@pytest.fixture(scope="module")
def wmeshes(tmp_path_factory):
    return well_meshes(tmp_path_factory.mktemp("wells"))


def injected_water_error(outdir, mesh) -> float:
    """A rate-controlled injector (0.01 m3/s of 20 degC water into rock at
    80 degC) through both layers of a closed box for 1e6 s: the water the
    two rocks store, int S dp - phi beta_f dT with each region's S and phi,
    over the water injected, less one."""
    from petthm.io.output import read_cell_regions
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fields", "pm,Tm",
                      "-thm_fe_degree", 1, *SANDSTONE, *GRANITE, *anisotropic(3),
                      "-thm_wells", "inj", "-thm_well_inj_rate", 0.01,
                      "-thm_well_inj_temperature", 20, "-thm_initial_temperature", 80,
                      "-thm_final_time", 1e6, "-thm_dt_initial", 1e5)
    assert s["status"] == "completed"
    x, cells, t, fields = read_output(str(outdir / "fields.h5"))
    granite = read_cell_regions(str(outdir)) == 1
    corners = x[cells]
    edges = corners[:, 1:] - corners[:, :1]
    volume = np.abs(np.linalg.det(edges)) / 6

    def storage(phi, alpha, E, nu):
        return phi * 4.5e-10 + (alpha - phi) * (1 - alpha) / (E / (3 * (1 - 2 * nu)))
    S = np.where(granite, storage(0.01, 0.5, 60e9, 0.2), storage(0.2, 0.9, 20e9, 0.3))
    B = np.where(granite, 0.01, 0.2) * 2.07e-4
    dp, dT = fields["pm"].ravel(), fields["Tm"].ravel() - 80.0
    stored = np.sum(volume * (S * dp[cells].mean(axis=1) - B * dT[cells].mean(axis=1)))
    return stored / (0.01 * t) - 1.0


def two_wells(outdir, mesh, ranks=1) -> tuple:
    """The 2D section (k = 1e-12 m2): an injector of 20 degC water into rock
    at 80 degC, 1e-4 m3/s (per metre), that turns producer at 5e6 s, and a
    producer at a bottom-hole pressure of 1 MPa below the initial 2 MPa;
    (history rows, summary)."""
    import csv
    _, s = run_petthm("reservoir", outdir, "-thm_mesh_file", mesh, "-thm_fields", "pm,Tm",
                      "-thm_fe_degree", 1, "-thm_wells", "inj,prod", "-thm_well_inj_rate", "1e-4,-1e-4",
                      "-thm_well_inj_times", "0,5e6", "-thm_rock_permeability", 1e-12,
                      "-thm_well_inj_temperature", 20, "-thm_well_prod_pressure", 1e6,
                      "-thm_initial_temperature", 80, "-thm_initial_pressure", 2e6, "-thm_rock_porosity", 0.1,
                      "-thm_final_time", 1e7, "-thm_dt_initial", 5e5, ranks=ranks)
    assert s["status"] == "completed"
    with open(outdir / "history.csv") as f:
        return list(csv.DictReader(f)), s


def test_an_injector_through_two_layers_stores_what_it_injects(tmp_path, wmeshes):
    """One bottom-hole pressure for the well's nodes in two rocks; the
    water balance is exact (no other inflow or outflow)."""
    assert abs(injected_water_error(tmp_path, wmeshes[3])) < 1e-9


def test_a_schedule_switches_the_rate_at_its_time_and_temperatures_stay_in_bounds(tmp_path, wmeshes):
    """The steps land on 5e6 s; the injector's rate is 1e-4 up to it and
    -1e-4 after; the producer's pressure is its 1 MPa; Tm stays within
    [T_inj, T0] (the bound-preserving transport with the wells' enthalpy)."""
    rows, s = two_wells(tmp_path, wmeshes[2])
    times = [float(r["time"]) for r in rows]
    assert 5e6 in times
    for r, t in zip(rows, times, strict=True):
        assert float(r["well_inj_rate"]) == (1e-4 if t <= 5e6 else -1e-4)
        assert float(r["well_prod_pressure"]) == 1e6
    assert float(rows[1]["well_prod_rate"]) < 0 and float(rows[-1]["well_inj_power"]) > 0
    assert s["bounds"]["Tm"]["violation_fraction"] <= 1e-6


def test_wells_on_two_ranks_equal_one(tmp_path, wmeshes):
    one, _ = two_wells(tmp_path / "one", wmeshes[2])
    two, _ = two_wells(tmp_path / "two", wmeshes[2], ranks=2)
    for key in ("well_inj_pressure", "well_prod_rate", "well_inj_temperature"):
        assert float(two[-1][key]) == pytest.approx(float(one[-1][key]), rel=1e-8), key


def disc_with_a_well(path: str, h: float, R: float = 500.0) -> str:
    """A 2D disc of radius R (region rock, boundary outer) with a point well at its centre."""
    from petthm.mesh.generate import _start, _write
    gmsh = _start("disc")
    occ = gmsh.model.occ
    _, pieces = occ.fragment([(2, occ.addDisk(0, 0, 0, R, R))], [(0, occ.addPoint(0, 0, 0))])
    occ.synchronize()
    gmsh.model.addPhysicalGroup(2, [e[1] for e in pieces[0] if e[0] == 2], 1, name="rock")
    gmsh.model.addPhysicalGroup(1, [e[1] for e in gmsh.model.getEntities(1)], 2, name="outer")
    gmsh.model.addPhysicalGroup(0, [e[1] for e in pieces[1]], 3, name="well")
    gmsh.option.setNumber("Mesh.MeshSizeMin", h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    return _write(gmsh, 2, path)


def thiem_errors(outdir, h: float) -> tuple[float, float]:
    """A well at the centre of a disc (R = 500 m, k = 1e-14 m2) takes
    1e-4 m3/s per metre, the rim held at p = 0; in steady state Thiem's
    p(r) = Q mu / (2 pi k) ln(R / r).  (The largest error of p at
    50 m < r < 450 m, and the bottom-hole pressure's, both relative to
    Thiem's pressure at the well's radius r_w = 0.1 m.)"""
    import csv
    import math
    outdir.mkdir(parents=True, exist_ok=True)
    mesh = disc_with_a_well(str(outdir / "disc.msh"), h)
    _, s = run_petthm("reservoir", outdir / "run", "-thm_mesh_file", mesh, "-thm_fields", "pm",
                      "-thm_fe_degree", 1, "-thm_wells", "well", "-thm_well_well_rate", 1e-4,
                      "-thm_bc_outer_pressure", 0, *STEADY,
                      "-thm_final_time", 2e10, "-thm_dt_max", 1e10)
    assert s["status"] == "completed"
    x, p = final(outdir / "run", "pm")
    r = np.linalg.norm(x, axis=1)

    def thiem(radius):
        return 1e-4 * 1e-3 / (2 * math.pi * 1e-14) * np.log(500.0 / radius)
    far = (r > 50) & (r < 450)
    with open(outdir / "run" / "history.csv") as f:
        pw = float(list(csv.DictReader(f))[-1]["well_well_pressure"])
    return (float(np.max(np.abs(p.ravel()[far] - thiem(r[far]))) / thiem(0.1)),
            float(pw / thiem(0.1) - 1.0))


def test_a_well_in_a_disc_draws_thiem_s_pressure(tmp_path):
    """The pressure away from the well converges to Thiem's (h = 50 m:
    4e-3, 25 m: 4e-4 of the well's drawdown); the bottom-hole pressure
    through Peaceman's index is within a few per cent of Thiem's at r_w."""
    far, well = thiem_errors(tmp_path, 25.0)
    assert far < 1e-3 and abs(well) < 0.05


@pytest.mark.parametrize("rate,warned", [(-1e-4, True), (-1e-6, False)])
def test_a_well_that_draws_its_pressure_below_boiling_is_reported(tmp_path, wmeshes, rate, warned):
    """A producer at 1e-4 m3/s per metre from rock of 1e-14 m2 draws its
    bottom-hole pressure below the vapour pressure of 80 degC water: one
    warning naming the well (the model has one phase); at 1e-6 m3/s none."""
    proc, s = run_petthm("reservoir", tmp_path, "-thm_mesh_file", wmeshes[2], "-thm_fields", "pm,Tm",
                         "-thm_fe_degree", 1, "-thm_wells", "prod", "-thm_well_prod_rate", rate,
                         "-thm_initial_temperature", 80, "-thm_initial_pressure", 2e6,
                         "-thm_final_time", 1e6, "-thm_dt_initial", 2.5e5)
    assert s["status"] == "completed"
    lines = [line for line in proc.stderr.splitlines() if line.startswith("warning:") and "well prod" in line]
    assert len(lines) == (1 if warned else 0), proc.stderr
    assert not warned or "is not liquid" in lines[0]


def test_a_mesh_of_ten_groups_or_more_keeps_every_boundary_whole(tmp_path):
    """Groups numbered 10 and up are regions and boundaries like any other
    (gmsh numbers groups in the order they are made): eight layers and four
    faces give the top face tag 12, and the column still becomes hydrostatic
    with its top held at p = 0."""
    layers = [(f"layer{k}", -1000.0 + 125.0 * (k + 1)) for k in range(8)]
    mesh = layered_deck_box(str(tmp_path / "eight.msh"), [0, -1000], [200, 0], 125, layers)
    assert hydrostatic_error(tmp_path / "run", mesh, 2, 1) < 1e-10
