"""A bad deck gets one line naming the option or group and what the mesh has
(docs/user-guide/reliability.md, "Decks"; ../shared/docs/reservoir.md)."""
import pytest

from conftest import run_petthm
from petthm.mesh.deckmesh import layered_deck_box

HOLD = [a for face in ("bottom", "west", "east", "south", "north")
        for a in (f"-thm_bc_{face}_normal_displacement", 0)]


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    d = tmp_path_factory.mktemp("deckbox")
    return layered_deck_box(str(d / "box.msh"), [0, 0, -300], [300, 300, 0], 150,
                            [("granite", -150.0), ("sandstone", 0.0)])


@pytest.fixture(scope="module")
def square(tmp_path_factory):
    return layered_deck_box(str(tmp_path_factory.mktemp("decksq") / "sq.msh"), [0, -300], [300, 0], 100)


def _error(tmp_path, *options):
    proc, _ = run_petthm("reservoir", tmp_path, *options, check=False)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and lines[0].startswith("petthm: error: "), proc.stderr
    return lines[0]


@pytest.mark.parametrize("options,words", [
    ((), ("needs -thm_mesh_file",)),
    (("-thm_bc_tpo_pressure", 0), ("-thm_bc_tpo_pressure", "no boundary 'tpo'", "did you mean top?",
                                   "west, east, south, north, bottom, top")),
    (("-thm_bc_top_presure", 0), ("-thm_bc_top_presure", "did you mean pressure?")),
    (("-thm_region_granit_rock_porosity", 0.1), ("-thm_region_granit_rock_porosity", "no region 'granit'",
                                                  "did you mean granite?",
                                                  "its regions: granite, sandstone")),
    (("-thm_region_granite_porosity", 0.1), ("-thm_region_granite_porosity", "a region takes",
                                             "did you mean rock_porosity?")),
    (("-thm_region_granite_rock_porosity", 1.5), ("-thm_region_granite_rock_porosity = 1.5",
                                                  "outside the accepted range")),
    (("-thm_region_sandstone_rock_permeability", "1e-14,1e-14,1e-14,2e-14,0,0"),
     ("-thm_region_sandstone_rock_permeability", "not positive semi-definite")),
    (("-thm_region_granite_rock_permeability", 0, "-thm_region_granite_rock_porosity", 0,
      "-thm_region_granite_rock_biot_coefficient", 1, *HOLD),
     ("region granite", "pressure is undetermined")),
    (("-thm_wells", "inj"), ("-thm_wells = inj", "no group 'inj' of dimension 1", "none")),
    (("-thm_bc_top_pressure", "(-z)*rho"), ("-thm_bc_top_pressure", "the name 'rho'", "accepted")),
    (("-thm_initial_temperature", "20+__import__(1)"), ("-thm_initial_temperature", "__import__",
                                                        "not accepted")),
    (("-thm_fields", "u,pf"), ("-thm_fields = u,pf", "pf needs fractures (-thm_fractures)")),
    (("-thm_fields", "u,pff"), ("-thm_fields", "'pff' is not a field of a deck", "did you mean pf?")),
    (("-thm_bc_top_pressure", 0, *HOLD), ("-thm_bc_top_pressure", "carries its heat",
                                          "-thm_bc_top_temperature")),
    (("-thm_fractures", "tpo"), ("-thm_fractures = tpo", "no group 'tpo'", "did you mean top?",
                                 "a fracture is a group of dimension 2")),
    (("-thm_fractures", "granite"), ("-thm_fractures = granite", "'granite' is a group of dimension 3")),
    (("-thm_fracture_top_aperture", 1e-3), ("-thm_fracture_top_aperture", "'top' is not a fracture",
                                            "give -thm_fractures top")),
    (("-thm_fields", "Tm", "-thm_bc_top_pressure", 0), ("-thm_bc_top_pressure", "a condition on pm",
                                                         "its fields: Tm")),
    (("-thm_fields", "u,Tm"), ("nothing holds u_x,y,z", "rigid body")),
    (("-thm_bc_bottom_normal_displacement", 0, "-thm_bc_west_normal_displacement", 0),
     ("nothing holds u_y",)),
    (("-thm_initial_temperature", "20+(-z)*0.5", *HOLD), ("-thm_initial_temperature", "170 degC",
                                                          "is not liquid water", "boiling")),
    (("-thm_gravity", 9.81, *HOLD), ("-thm_insitu_stress = 0", "does not balance gravity",
                                     "region granite")),
    (("-thm_rock_permeability", "1e-14,2e-14,3e-14,4e-14"), ("-thm_rock_permeability", "1, 3 or 6 values")),
])
def test_a_bad_deck_is_one_line_naming_what_is_wrong(tmp_path, box, options, words):
    first = () if options == () else ("-thm_mesh_file", box)
    msg = _error(tmp_path, *first, *options)
    assert all(w in msg for w in words), msg


@pytest.fixture(scope="module")
def wellbox(tmp_path_factory):
    return layered_deck_box(str(tmp_path_factory.mktemp("deckwell") / "wb.msh"), [0, 0, -300], [300, 300, 0],
                            150, wells=[("inj", [(150, 150, -250), (150, 150, -50)])])


@pytest.mark.parametrize("options,words", [
    (("-thm_wells", "inj"), ("well inj", "either -thm_well_inj_rate or -thm_well_inj_pressure")),
    (("-thm_wells", "inj", "-thm_well_inj_rate", "0.01,0"), ("-thm_well_inj_times", "one time per value")),
    (("-thm_wells", "inj", "-thm_well_inj_rate", "0.01,0", "-thm_well_inj_times", "5,10"),
     ("increasing times from 0",)),
    (("-thm_wells", "inj", "-thm_well_inj_rate", 0.01, *HOLD), ("well inj injects",
                                                                 "-thm_well_inj_temperature")),
    (("-thm_well_inj_rate", 0.01), ("-thm_well_inj_rate", "not in -thm_wells")),
    (("-thm_well_inx_rate", 0.01), ("no well 'inx'", "did you mean inj?")),
    (("-thm_wells", "inj", "-thm_well_inj_pressure", 1e6, "-thm_fields", "Tm"), ("needs pm",)),
])
def test_a_bad_well_is_one_line_naming_what_is_wrong(tmp_path, wellbox, options, words):
    msg = _error(tmp_path, "-thm_mesh_file", wellbox, *options)
    assert all(w in msg for w in words), msg


def test_z_in_a_2d_deck_is_an_unknown_symbol(tmp_path, square):
    msg = _error(tmp_path, "-thm_mesh_file", square, "-thm_fields", "Tm",
                 "-thm_initial_temperature", "20+(-z)")
    assert "-thm_initial_temperature" in msg and "the name 'z'" in msg


def test_a_cell_in_no_region_is_an_error(tmp_path):
    gmsh = pytest.importorskip("gmsh")
    path = str(tmp_path / "part.msh")
    gmsh.initialize(["-v", "0"])
    try:
        a = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.addBox(1, 0, 0, 1, 1, 1)
        gmsh.model.occ.removeAllDuplicates()
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [a], 1, name="left")
        gmsh.option.setNumber("Mesh.SaveAll", 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
        gmsh.model.mesh.generate(3)
        gmsh.write(path)
    finally:
        gmsh.finalize()
    msg = _error(tmp_path / "run", "-thm_mesh_file", path)
    assert "belong to no named region" in msg and "left" in msg


def test_a_normal_displacement_on_a_face_off_the_axes_is_an_error(tmp_path):
    mesh = layered_deck_box(str(tmp_path / "turned.msh"), [0, 0, -300], [300, 300, 0], 150, rotation=20.0)
    msg = _error(tmp_path / "run", "-thm_mesh_file", mesh, *HOLD)
    assert "boundary 'west' is not a plane normal" in msg and "-thm_bc_west_displacement" in msg


def test_a_restart_keeps_the_boundary_values(tmp_path, box):
    """-thm_bc_NAME_* are physics options: a restart that changes one is
    refused naming it; the same values continue the run."""
    opts = ("-thm_mesh_file", box, "-thm_fields", "Tm", "-thm_initial_temperature", 80,
            "-thm_bc_top_temperature", 20, "-thm_final_time", 1e7)
    _, s = run_petthm("reservoir", tmp_path, *opts, "-ts_max_steps", 2, check=False)
    assert s["status"] == "stopped" and s["provenance"]["parameters"]["-thm_bc_top_temperature"] == "20"
    proc, _ = run_petthm("reservoir", tmp_path, *opts[:-4], "-thm_bc_top_temperature", 30, "-thm_final_time",
                         1e7, "-thm_restart", tmp_path, check=False)
    assert "-thm_bc_top_temperature" in proc.stderr and "differ" in proc.stderr, proc.stderr
    _, s = run_petthm("reservoir", tmp_path, *opts, "-thm_restart", tmp_path)
    assert s["status"] == "completed"


def test_the_geometry_tool_writes_a_mesh_and_a_starter_deck(tmp_path):
    """python -m petthm.run.deckbox: the mesh and an options file naming it;
    with a boundary value filled in, the deck runs."""
    import subprocess
    import sys

    from conftest import ROOT

    def tool(*args):
        return subprocess.run([sys.executable, "-m", "petthm.run.deckbox", *args], cwd=ROOT,
                              capture_output=True, text=True)
    out = tmp_path / "res.msh"
    proc = tool("--lower", "0,-300", "--upper", "300,0", "--size", "100",
                "--layers", "granite:-150,sandstone:0", "--well", "inj:150,-200", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    opts = (tmp_path / "res.opts").read_text()
    assert f"-thm_mesh_file {out}" in opts and "# -thm_bc_top_temperature VALUE" in opts
    assert "# -thm_region_granite_rock_permeability VALUE" in opts and "# -thm_wells inj" in opts
    _, s = run_petthm("reservoir", tmp_path / "run", "-options_file", tmp_path / "res.opts",
                      "-thm_gravity", 0, "-thm_fields", "Tm", "-thm_bc_top_temperature", 10,
                      "-ts_max_steps", 2, check=False)
    assert s["status"] == "stopped" and s["change"]["Tm_change_max"] > 0
    bad = tool("--lower", "0,0", "--upper", "1,1,1", "--size", "1", "--out", str(tmp_path / "x.msh"))
    assert bad.returncode == 2 and bad.stderr.startswith("petthm: error: --lower and --upper")


@pytest.fixture(scope="module")
def fracbox(tmp_path_factory):
    """A box with a square fracture 'crack' at 150 m depth, a well 'w' through
    it and a well 'along' inside it."""
    return layered_deck_box(str(tmp_path_factory.mktemp("deckfrac") / "fb.msh"), [0, 0, -300], [300, 300, 0],
                            150, wells=[("w", [(150, 150, -250), (150, 150, -50)]),
                                        ("along", [(100, 150, -150), (200, 150, -150)])],
                            fractures=[("crack", [(75, 75, -150), (225, 75, -150), (225, 225, -150),
                                                  (75, 225, -150)])])


FLOW_HEAT = ("-thm_fields", "pm,pf,Tm,Tf")


@pytest.mark.parametrize("options,words", [
    (("-thm_fractures", "crack"), ("rock mechanics of a fractured deck", "leave u out")),
    (("-thm_fractures", "crack", "-thm_fields", "pm,Tm"), ("-thm_fields = pm,Tm", "needs pf")),
    (("-thm_fractures", "crack", "-thm_fields", "pm,pf,Tm"), ("Tm needs Tf",)),
    (("-thm_fractures", "crack", "-thm_fields", "pf,Tf"), ("Tf needs Tm",)),
    (("-thm_fractures", "crack,crack", *FLOW_HEAT), ("'crack' is listed twice",)),
    (("-thm_fractures", "crack", "-thm_fracture_crack_friction", 0.6, *FLOW_HEAT),
     ("-thm_fracture_crack_friction", "deformable fractures", "not part of a deck yet")),
    (("-thm_fractures", "crack", "-thm_fracture_crack_aperature", 1e-3, *FLOW_HEAT),
     ("-thm_fracture_crack_aperature", "a fracture takes aperture", "did you mean aperture?")),
    (("-thm_fractures", "crack", "-thm_fracture_crack_aperture", -1, *FLOW_HEAT),
     ("-thm_fracture_crack_aperture = -1",)),
    (("-thm_fractures", "crack", "-thm_bc_crack_pressure", 0, *FLOW_HEAT),
     ("-thm_bc_crack_pressure", "crack is a fracture", "not a boundary")),
    (("-thm_fractures", "crack", "-thm_wells", "along", "-thm_well_along_pressure", 1e6, *FLOW_HEAT),
     ("well along runs inside fracture crack", "a well along a fracture is not part of a deck yet")),
    (("-thm_fractures", "crack", "-thm_wells", "w", "-thm_well_w_pressure", 1e6, "-thm_fields", "pf,Tm,Tf"),
     ("-thm_wells = w", "a well in the rock needs pm", "well w has nodes off the fractures")),
])
def test_a_bad_fracture_is_one_line_naming_what_is_wrong(tmp_path, fracbox, options, words):
    msg = _error(tmp_path, "-thm_mesh_file", fracbox, *options)
    assert all(w in msg for w in words), msg


def test_the_geometry_tool_writes_a_fractured_deck_that_runs(tmp_path):
    """--fracture embeds a named fracture; the starter deck names it, and with
    the boundaries' values filled in it runs."""
    import subprocess
    import sys

    from conftest import ROOT
    out = tmp_path / "frac.msh"
    tool = [sys.executable, "-m", "petthm.run.deckbox", "--lower", "0,-100", "--upper", "200,0",
            "--size", "25", "--fracture", "crack:0,-50/200,-50", "--out", str(out)]
    proc = subprocess.run(tool, cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    opts = (tmp_path / "frac.opts").read_text()
    assert "-thm_fractures crack\n" in opts and "# -thm_fracture_crack_aperture A" in opts
    help_command = [sys.executable, "-m", "petthm", "reservoir", "-thm_mesh_file", str(out), "-help"]
    listed = subprocess.run(help_command, cwd=ROOT, capture_output=True, text=True).stdout
    assert "-thm_fractures " in listed and "-thm_fracture_<NAME>_aperture" in listed
    _, s = run_petthm("reservoir", tmp_path / "run", "-options_file", tmp_path / "frac.opts",
                      "-thm_gravity", 0, "-thm_bc_west_pressure", 1e6, "-thm_bc_west_temperature", 20,
                      "-thm_bc_east_pressure", 0, "-thm_bc_east_temperature", 80,
                      "-thm_initial_temperature", 80, "-ts_max_steps", 2, check=False)
    assert s["status"] == "stopped" and s["change"]["Tf_change_max"] > 0
