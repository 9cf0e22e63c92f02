"""The examples gallery (examples/README.md): each example's commands run
as its README says (the mesh, then a few steps of the deck; the whole runs
and their times are the README's)."""
import os
import subprocess
import sys

from conftest import ROOT, run_petthm


def test_the_egs_doublet_meshes_and_starts(tmp_path):
    env = dict(os.environ, PATH=f"{os.path.dirname(sys.executable)}:{os.environ['PATH']}")
    proc = subprocess.run(["bash", "examples/egs_doublet/mesh.sh"], cwd=ROOT, env=env, capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stderr
    _, s = run_petthm("reservoir", tmp_path, "-options_file", f"{ROOT}/examples/egs_doublet/deck.opts",
                      "-thm_mesh_file", f"{ROOT}/output/egs_doublet_mesh/egs_doublet.msh", "-ts_max_steps", 3,
                      check=False)
    assert s["status"] == "stopped" and s["steps"] == 3
    with open(tmp_path / "history.csv") as f:
        header = f.readline().strip().split(",")
    assert {f"well_inj_fracture_f{x}_rate" for x in (300, 450, 600, 750)} <= set(header)
