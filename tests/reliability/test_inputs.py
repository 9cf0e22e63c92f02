"""A strict command line and physically possible inputs (docs/user-guide/reliability.md,
"Command line" and "Inputs"): a stray word, a second value or a list where a
number is expected is an error naming it; an options file gets the same
rules with its file and line; water must be liquid (IAPWS-IF97 region 1);
lengths must fit the domain."""
import pytest

from conftest import LAUWERIER_COARSE, run_petthm

LAUWERIER = (*LAUWERIER_COARSE, "-thm_final_time", 1e6)


def _error(proc):
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1 and lines[0].startswith("petthm: error: "), \
        proc.stdout + proc.stderr
    assert proc.stdout == "" or "Traceback" not in proc.stdout
    return lines[0]


def test_an_options_file_given_without_its_option_is_an_error(tmp_path):
    """``python -m petthm heat_erfc my.opts``: the forgotten -options_file."""
    import os
    import subprocess
    import sys

    from conftest import MPI_ENV
    (tmp_path / "my.opts").write_text("-thm_final_time 10\n")
    proc = subprocess.run([sys.executable, "-m", "petthm", "heat_erfc", "my.opts"], cwd=tmp_path,
                          env=dict(os.environ, **MPI_ENV), capture_output=True, text=True, timeout=120)
    msg = _error(proc)
    assert "unexpected argument 'my.opts' (did you mean -options_file my.opts?)" in msg, msg
    assert not (tmp_path / "output").exists()


@pytest.mark.parametrize("args,words", [
    (("-thm_final_time", "10", "20"), ("option -thm_final_time takes one value, not 2 (10 20)",)),
    (("-thm_rock_conductivity", "5", "6"), ("-thm_rock_conductivity takes one value",)),
    (("-thm_rock_conductivity", "5,6"), ("-thm_rock_conductivity", "'5,6'")),
    (("-ksp_rtol", "1e-8", "1e-9"), ("option -ksp_rtol takes one value",)),
])
def test_stray_words_and_extra_values_are_errors(tmp_path, args, words):
    """A positional argument other than the scene (the forgotten
    -options_file), a second value for an option (PETSc keeps the first and
    ignores the rest), a list where a number is expected."""
    proc, _ = run_petthm("heat_erfc", tmp_path / "run", *args, check=False)
    msg = _error(proc)
    assert all(w in msg for w in words), msg
    assert not (tmp_path / "run").exists()


def test_negative_numbers_are_values(tmp_path):
    """-5 after an option is its value, not an option (as PETSc reads it)."""
    proc, s = run_petthm("heat_erfc", tmp_path, "-thm_final_time", 1e3, "-thm_surface_temperature", "5",
                         "-ksp_atol", "-1")
    assert s["status"] == "completed"


@pytest.mark.parametrize("text,words", [
    ("-thm_final_time 10 20\n", ("line 1", "-thm_final_time takes one value, not 2 (10 20)")),
    ("# comment\n-thm_quiet\n-thm_surface_temperature 5 # degC\n-ksp_type gmres cg\n",
     ("line 4", "-ksp_type takes one value")),
    ("-options_file NESTED\n", ("nested.opts' line 2", "-thm_x takes one value")),
])
def test_an_options_file_follows_the_same_rules_with_file_and_line(tmp_path, text, words):
    nested = tmp_path / "nested.opts"
    nested.write_text("-thm_final_time 100\n-thm_x 1 2\n")
    opts = tmp_path / "bad.opts"
    opts.write_text(text.replace("NESTED", str(nested)))
    proc, _ = run_petthm("heat_erfc", tmp_path / "run", "-options_file", opts, check=False)
    msg = _error(proc)
    assert all(w in msg for w in words), msg


def test_a_quoted_value_with_spaces_is_one_value(tmp_path):
    opts = tmp_path / "ok.opts"
    opts.write_text('-thm_final_time 1e3\n-thm_fracture_heat_exchange "equilibrium"\n')
    from petthm.__main__ import bad_options_file
    assert bad_options_file(str(opts)) is None


@pytest.mark.parametrize("scene,args,words", [
    ("lauwerier", ("-thm_injection_temperature", -300),
     ("-thm_injection_temperature = -300 degC", "1.10133 MPa", "0 degC < T", "184.1 degC, boiling")),
    ("lauwerier", ("-thm_injection_temperature", 1000), ("-thm_injection_temperature = 1000 degC",)),
    ("lauwerier", ("-thm_initial_temperature", 200, "-thm_initial_pressure", 0,
                   "-thm_production_pressure", 0),
     ("-thm_initial_temperature = 200 degC", "0.101325 MPa", "-thm_initial_pressure = 0 Pa, gauge",
      "99.97 degC")),
    ("inclined_penny", ("-thm_initial_temperature", 360),
     ("360 degC", "T <= 350 degC, the edge of region 1")),
    ("heat_erfc", ("-thm_surface_temperature", -5), ("-thm_surface_temperature = -5 degC",)),
    ("heat_advection", ("-thm_injection_temperature", 190), ("scene heat_advection's water at 1e+06 Pa",)),
    ("lauwerier", ("-thm_initial_pressure", -2e5, "-thm_production_pressure", -2e5),
     ("no liquid water at -0.098675 MPa",)),
])
def test_water_that_is_not_liquid_is_refused(tmp_path, scene, args, words):
    """Temperatures where there is water: IAPWS-IF97 region 1 at the
    absolute initial pressure (gauge + 101 325 Pa), before anything is built."""
    proc, _ = run_petthm(scene, tmp_path / "run", *args, check=False)
    msg = _error(proc)
    assert all(w in msg for w in words), msg
    assert not (tmp_path / "run").exists()


def test_the_paper_scenes_water_is_liquid(tmp_path):
    """Scene 3's case 2 (250 degC at 20 MPa) passes the check (in this
    process: the options database emptied of other tests' options first)."""
    from petsc4py import PETSc

    from conftest import _only_options
    from petthm.run.driver import make_scene
    _only_options()
    opts = PETSc.Options()
    for case in (1, 2, 3):
        opts.setValue("thm_scene3_case", case)
        make_scene("inclined_penny")
    opts.delValue("thm_scene3_case")


@pytest.mark.parametrize("args,words", [
    (("-thm_mesh_size", 1000), ("-thm_mesh_size = 1000 m is larger than the domain", "at most 120 m")),
    (("-thm_lauwerier_fracture_size", 500), ("-thm_lauwerier_fracture_size = 500 m",)),
    (("-thm_well_radius", 1e4), ("-thm_well_radius = 10000 m does not fit in the domain",)),
])
def test_lengths_that_do_not_fit_the_domain_are_refused(tmp_path, args, words):
    proc, _ = run_petthm(LAUWERIER[0], tmp_path / "run", *LAUWERIER[1:], *args, check=False)
    msg = _error(proc)
    assert all(w in msg for w in words), msg


def test_read_output_takes_the_xdmf_or_the_h5_and_names_a_file_it_cannot_read(tmp_path):
    from petthm.io.output import read_output
    run_petthm(LAUWERIER[0], tmp_path / "run", *LAUWERIER[1:])
    a = read_output(str(tmp_path / "run" / "fields.xdmf"))
    b = read_output(str(tmp_path / "run" / "fields.h5"))
    assert a[2] == b[2] == 1e6 and (a[0] == b[0]).all()
    with pytest.raises(ValueError, match="mesh.h5 is not a readable petthm field series"):
        read_output(str(tmp_path / "run" / "mesh.msh").replace(".msh", ".h5"))
    with pytest.raises(IndexError, match="has outputs 0 to"):
        read_output(str(tmp_path / "run" / "fields.h5"), 10 ** 6)
