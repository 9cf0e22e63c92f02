"""What a restart continues (docs/user-guide/reliability.md, "Restart"): the same
problem (physics, mesh and discretisation options and the mesh file kept;
solver, output and run-control options and a later end time may change),
a completed run is left as it is, a restarted run's summary reports the
whole run, and damaged files are named."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import LAUWERIER_COARSE, MPI_ENV, ROOT, folder_digests, read_json, read_text, run_petthm

LAUWERIER = (*LAUWERIER_COARSE, "-thm_final_time", 1e6)


def _error(proc):
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1 and lines[0].startswith("petthm: error: "), proc.stderr
    return lines[0]


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished coarse lauwerier run (copied by each test that changes it)."""
    out = tmp_path_factory.mktemp("finished") / "run"
    run_petthm(LAUWERIER[0], out, *LAUWERIER[1:])
    return out


def _copy(src, dst):
    import shutil
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns(".petthm.lock"))
    return dst


def test_a_restart_that_changes_the_problem_is_refused_listing_each_difference(finished, tmp_path):
    """A changed physics option, mesh size, -dm_refine, element degree and
    time scheme: one line naming each, old -> new; nothing is changed."""
    out = _copy(finished, tmp_path / "run")
    before = folder_digests(out)
    proc, _ = run_petthm(LAUWERIER[0], out, *LAUWERIER[1:], "-thm_restart", out, "-thm_final_time", 2e6,
                         "-thm_rock_conductivity", 5, "-thm_mesh_size", 10, "-dm_refine", 1,
                         "-thm_fe_degree", 1, "-ts_type", "bdf", check=False)
    msg = _error(proc)
    for change in ("-thm_rock_conductivity 2.88 -> 5.0 (physics)", "-thm_mesh_size 20.0 -> 10.0 (mesh)",
                   "-dm_refine (not set) -> 1 (mesh)", "-thm_fe_degree 2 -> 1 (discretisation)",
                   "-ts_type (not set) -> bdf (discretisation)"):
        assert change in msg, msg
    assert folder_digests(out) == before


def test_a_restart_may_change_solver_output_and_run_control_options_and_a_later_end_time(finished, tmp_path):
    out = _copy(finished, tmp_path / "run")
    _, s = run_petthm(LAUWERIER[0], out, *LAUWERIER[1:], "-thm_restart", out, "-thm_final_time", 2e6,
                      "-ksp_rtol", 1e-12, "-thm_output_interval", 3, "-thm_checkpoint_interval", 2,
                      "-thm_pc_reuse", "off")
    assert s["status"] == "completed" and s["final_time"] == 2e6
    assert s["restarted_from"]["time"] == 1e6


def test_a_changed_mesh_file_is_refused(finished, tmp_path):
    out = _copy(finished, tmp_path / "run")
    with open(out / "mesh.msh", "a") as f:
        f.write("\n")
    proc, _ = run_petthm(LAUWERIER[0], out, *LAUWERIER[1:], "-thm_restart", out, "-thm_final_time", 2e6,
                         check=False)
    assert "mesh.msh' is not the one the checkpoint's run read" in _error(proc)


def test_restarting_a_completed_run_changes_nothing(finished, tmp_path):
    out = _copy(finished, tmp_path / "run")
    before = folder_digests(out)
    proc, _ = run_petthm(LAUWERIER[0], out, *LAUWERIER[1:], "-thm_restart", out)
    assert "has reached its end time" in proc.stdout and "nothing to continue" in proc.stdout
    assert folder_digests(out) == before


def test_an_end_time_before_the_checkpoint_is_refused(finished, tmp_path):
    out = _copy(finished, tmp_path / "run")
    proc, _ = run_petthm(LAUWERIER[0], out, *LAUWERIER[1:], "-thm_restart", out, "-thm_final_time", 5e5,
                         check=False)
    assert "past the end time" in _error(proc)


@pytest.mark.parametrize("damage", ["random", "truncated", "empty"])
@pytest.mark.parametrize("name", ["checkpoint.h5", "fields.h5"])
def test_a_damaged_checkpoint_or_field_file_is_a_one_line_error_naming_it(finished, tmp_path, name, damage):
    out = _copy(finished, tmp_path / "run")
    path = out / name
    data = path.read_bytes()
    path.write_bytes({"random": np.random.default_rng(1).bytes(len(data)), "truncated": data[:len(data) // 2],
                      "empty": b""}[damage])
    proc, _ = run_petthm(LAUWERIER[0], out, *LAUWERIER[1:], "-thm_restart", out, "-thm_final_time", 2e6,
                         check=False)
    msg = _error(proc)
    assert str(path) in msg and ("truncated or damaged" in msg), msg
    assert "options of the original run" not in msg


#: scenes whose monitors gather over the steps (their ``carried`` state): small, fast settings (a
#: variant in brackets after the scene's name)
WHOLE_RUN = {
    "lauwerier": (LAUWERIER[1:], 40),
    "terzaghi": (("-thm_fe_degree", 1), 6),
    "mandel": (("-thm_fe_degree", 1), 10),
    "leakoff_1d": ((), 15),
    "fracture_inflation": (("-thm_fe_degree", 1), 3),
    "heat_advection": (("-thm_fe_degree", 1), 20),
    "heat_advection[limited]": (("-thm_fe_degree", 1, "-thm_heat_transport", "limited"), 20),  # passes
    "thermal_stress": (("-thm_fe_degree", 1), 10),
    "friction_patch": (("-thm_fe_degree", 1), 2),
    "contact_patch": (("-thm_fe_degree", 1), 2),
}
#: summary.json entries that describe the process, not the run's results
PER_PROCESS = {"wall_time", "wall_time_whole_run", "solver_costs", "peak_memory_mb", "provenance",
               "restarted_from", "pc_rebuilds_forced", "snes_iterations", "ksp_iterations", "reason"}


def _same(a, b, path=""):
    """Whether two summary values agree (numbers to 1e-8 of their size or 1e-11)."""
    if isinstance(a, dict) and isinstance(b, dict):
        assert set(a) == set(b), (path, set(a) ^ set(b))
        for k in a:
            _same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list) and isinstance(b, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=False)):
            _same(x, y, f"{path}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert a is not None and b is not None, (path, a, b)
        close = abs(a - b) <= 1e-8 * max(abs(a), abs(b)) + 1e-11
        assert (math.isnan(a) and math.isnan(b)) or close, (path, a, b)
    else:
        assert a == b, (path, a, b)


@pytest.mark.parametrize("scene", sorted(WHOLE_RUN))
def test_a_restarted_run_reports_the_whole_run(tmp_path, scene):
    """Stopped by -ts_max_steps (status stopped, exit 4), then continued
    with -thm_restart: summary.json equals the uninterrupted run's (the
    scene's monitors over all steps: worst values, samples, peaks, the
    initial volume; errors against the reference at the end), and the
    iterations and the limited heat transport's settling passes are
    history.csv's sums over all steps."""
    options, steps = WHOLE_RUN[scene]
    scene = scene.split("[")[0]
    options = (*options, "-thm_pc_reuse", "off")       # one solver path in every run (auto decides by timing)
    _, ref = run_petthm(scene, tmp_path / "ref", *options)
    proc, s = run_petthm(scene, tmp_path / "run", *options, "-ts_max_steps", steps, check=False)
    assert proc.returncode == 4 and s["status"] == "stopped" and "-ts_max_steps" in s["message"], proc.stderr
    proc, s = run_petthm(scene, tmp_path / "run", *options, "-thm_restart", tmp_path / "run")
    assert s["restarted_from"]["step"] == steps
    _same({k: v for k, v in s.items() if k not in PER_PROCESS},
          {k: v for k, v in ref.items() if k not in PER_PROCESS})
    rows = read_text(tmp_path / "run" / "history.csv").splitlines()
    header = rows[0].split(",")
    sums = {k: sum(int(float(r.split(",")[header.index(k)])) for r in rows[1:])
            for k in ("snes_its", "ksp_its", "settling_passes") if k in header}
    assert [s["snes_iterations"], s["ksp_iterations"]] == [sums["snes_its"], sums["ksp_its"]]
    assert s["limiter_settling_passes"] == sums.get("settling_passes")
    if "error" in ref:
        assert "errors against the reference:" in proc.stdout
    assert read_json(tmp_path / "run" / "summary.json")["status"] == "completed"


def test_the_whole_run_check_fails_when_the_checkpoint_forgets_the_monitors(tmp_path):
    """Negative control of the test above: the first part of the run writes
    checkpoints without the monitors' carried state (tests/reliability/
    faults.py, forget-carried); the restarted run's summary then differs
    from the uninterrupted run's, and the comparison says so."""
    scene, options = "lauwerier", (*LAUWERIER[1:], "-thm_pc_reuse", "off")
    _, ref = run_petthm(scene, tmp_path / "ref", *options)
    first = [sys.executable, os.path.join(ROOT, "tests", "reliability", "faults.py"), "forget-carried", "0",
             scene, "-thm_output_dir", str(tmp_path / "run"), "-thm_quiet", *map(str, options),
             "-ts_max_steps", "40"]
    proc = subprocess.run(first, cwd=ROOT, env=dict(os.environ, **MPI_ENV), capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 4, proc.stderr
    _, s = run_petthm(scene, tmp_path / "run", *options, "-thm_restart", tmp_path / "run")
    with pytest.raises(AssertionError):
        _same({k: v for k, v in s.items() if k not in PER_PROCESS},
              {k: v for k, v in ref.items() if k not in PER_PROCESS})
