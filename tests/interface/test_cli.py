"""Command line: help, and one-line errors that name the problem."""
import subprocess
import sys

import pytest

from conftest import ROOT, run_petthm


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "petthm", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)


def test_help_lists_scenes():
    p = _cli("-help")
    assert p.returncode == 0
    for name in ("heat_mms", "heat_erfc", "heat_advection", "lauwerier", "rigid_fracture", "leakoff_heat"):
        assert name in p.stdout


def test_scene_help_lists_parameters_with_units_and_defaults():
    p = _cli("heat_erfc", "-help")
    assert p.returncode == 0
    line = next(l for l in p.stdout.splitlines() if "-thm_rock_conductivity" in l)
    assert "2.9" in line and "W/(m K)" in line


def _one_line_error(proc):
    err = [l for l in proc.stderr.strip().splitlines() if l.strip()]
    assert proc.returncode == 2, proc.stderr + proc.stdout
    assert len(err) == 1, proc.stderr
    return err[0]


def test_misspelt_thm_option_is_an_error(tmp_path):
    proc, _ = run_petthm("heat_mms", tmp_path, "-thm_rock_conductivty", "2", check=False)
    msg = _one_line_error(proc)
    assert "unknown option -thm_rock_conductivty" in msg and "-thm_rock_conductivity" in msg


def test_misspelt_petsc_option_is_an_error(tmp_path):
    proc, _ = run_petthm("heat_mms", tmp_path, "-ksp_tpye", "cg", check=False)
    assert "option -ksp_tpye was not used" in _one_line_error(proc)


def test_missing_mesh_file_is_an_error(tmp_path):
    proc, _ = run_petthm("heat_mms", tmp_path, "-thm_mesh_file", tmp_path / "nope.msh", check=False)
    msg = _one_line_error(proc)
    assert "nope.msh" in msg and "does not exist" in msg and "-thm_mesh_file" in msg


@pytest.mark.parametrize("value", ["-1", "inf", "nan"])
def test_out_of_range_or_non_finite_conductivity_is_an_error(tmp_path, value):
    proc, _ = run_petthm("heat_erfc", tmp_path, "-thm_rock_conductivity", value, check=False)
    msg = _one_line_error(proc)
    assert f"-thm_rock_conductivity = {float(value)}" in msg and "(0, inf)" in msg


def test_missing_options_file_is_an_error(tmp_path):
    proc, _ = run_petthm("heat_mms", tmp_path, "-options_file", tmp_path / "x.opts", check=False)
    assert "x.opts" in _one_line_error(proc)


def test_unknown_scene_is_an_error(tmp_path):
    proc, _ = run_petthm("heat_nope", tmp_path, check=False)
    assert "unknown scene 'heat_nope'" in _one_line_error(proc)


@pytest.mark.parametrize("opts,words", [
    (("-thm_fluid_viscosity", "foo"), ("-thm_fluid_viscosity", "water")),
    (("-thm_fracture_heat_exchange", "-3"), ("-thm_fracture_heat_exchange", "nusselt")),
    (("-thm_fracture_heat_exchange", "nusselt"), ("-thm_fracture_heat_exchange", "permeable")),
    (("-thm_rock_permeability", "1,2,3"), ("-thm_rock_permeability", "1 or 2 values")),
])
def test_bad_fracture_input_is_a_one_line_error(tmp_path, opts, words):
    proc, _ = run_petthm("rigid_fracture", tmp_path, *opts, "-thm_mesh_size", 60,
                         "-thm_scene1_fracture_size", 10, check=False)
    msg = _one_line_error(proc)
    assert all(w in msg for w in words), msg
