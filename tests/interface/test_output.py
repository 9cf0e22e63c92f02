"""Run output: summary.json, history.csv and XDMF that meshio reads back."""

import meshio
import numpy as np
import pytest

from conftest import read_csv, run_petthm


@pytest.mark.parametrize("dim,degree,size,cell", [(2, 2, 0.125, "triangle6"), (3, 2, 0.25, "tetra10"),
                                                  (2, 1, 0.0625, "triangle")])
def test_fields_xdmf_reads_back(tmp_path, dim, degree, size, cell):
    _, s = run_petthm("heat_mms", tmp_path, "-thm_mms_dim", dim, "-thm_fe_degree", degree,
                      "-thm_mesh_size", size)
    with meshio.xdmf.TimeSeriesReader(str(tmp_path / "fields.xdmf")) as r:
        points, cells = r.read_points_cells()
        assert cells[0].type == cell
        nsteps = r.num_steps
        t, pd, _ = r.read_data(nsteps - 1)
    assert t == pytest.approx(1.0)
    # the written field is the manufactured solution up to the discretisation error
    x = points[:, :dim]
    g = np.sin(np.pi * x[:, 0]) * np.cos(np.pi * x[:, 1]) + x[:, 0] * x[:, 1]
    if dim == 3:
        g = g * np.cos(0.5 * np.pi * x[:, 2]) + x[:, 2] ** 2
    exact_c = 300 + 10 * 2 * g - 273.15
    # (a wrong node order would give errors of the order of the 40 K range)
    assert np.abs(pd["Tm"] - exact_c).max() < 0.5


def test_summary_and_history_contents(tmp_path):
    _, s = run_petthm("heat_mms", tmp_path)
    for key in ("scene", "petthm_version", "petsc_version", "petsc4py_version", "ranks", "fields",
                "dofs", "steps", "rejected_steps", "snes_iterations", "ksp_iterations",
                "wall_time", "final_time", "status", "error"):
        assert key in s, key
    assert s["status"] == "completed" and s["dofs"]["Tm"] > 0
    assert set(s["wall_time"]) >= {"mesh", "setup", "solve", "output", "total"}
    rows = (read_csv(tmp_path / "history.csv"))
    assert list(rows[0])[:6] == ["step", "time", "dt", "snes_its", "ksp_its", "wall"]
    assert [int(r["step"]) for r in rows] == list(range(s["steps"] + 1))
    assert sum(int(r["snes_its"]) for r in rows) == s["snes_iterations"]


def test_log_view_shows_the_stages(tmp_path):
    proc, _ = run_petthm("heat_mms", tmp_path, "-log_view")
    for stage in ("mesh", "setup", "solve", "output"):
        assert f": {stage}:" in proc.stdout or f"{stage}:" in proc.stdout
    assert "thm.jacobian" in proc.stdout and "thm.residual" in proc.stdout


def test_dm_refine_refines_uniformly(tmp_path):
    _, coarse = run_petthm("heat_mms", tmp_path / "c", "-thm_mesh_size", 0.25)
    _, fine = run_petthm("heat_mms", tmp_path / "f", "-thm_mesh_size", 0.25, "-dm_refine", 1)
    assert fine["cells"] == 4 * coarse["cells"]
    assert fine["error"]["Tm_l2"] < coarse["error"]["Tm_l2"] / 6     # P2: ~8x per halving
