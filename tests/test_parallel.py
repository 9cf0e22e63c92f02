"""2 and 3 ranks reproduce the serial result (fields compared node by node)."""
import h5py
import numpy as np
import pytest

from conftest import run_petthm

TIGHT = ("-ksp_rtol", "1e-13", "-ksp_atol", "1e-15", "-snes_rtol", "1e-10", "-snes_atol", "1e-10")


def final_field(outdir, name="Tm"):
    """Final nodal field sorted by node coordinates (numbering differs across ranks)."""
    with h5py.File(outdir / "fields.h5", "r") as h5:
        xyz = h5["mesh/geometry"][...]
        steps = sorted(h5[f"fields/{name}"], key=int)
        v = h5[f"fields/{name}/{steps[-1]}"][...]
    order = np.lexsort(np.round(xyz, 12).T[::-1])
    return xyz[order], v[order]


@pytest.mark.parallel
@pytest.mark.parametrize("scene,opts", [
    ("heat_mms", ("-thm_mms_dim", 2, "-thm_mesh_size", 0.0625)),
    ("heat_mms", ("-thm_mms_dim", 3, "-thm_mesh_size", 0.25, "-thm_fe_degree", 1)),
    ("heat_advection", ("-thm_final_time", 2e6)),
])
def test_parallel_matches_serial(tmp_path, scene, opts):
    ref = None
    for n in (1, 2, 3):
        _, s = run_petthm(scene, tmp_path / f"n{n}", *opts, *TIGHT, ranks=n)
        assert s["status"] == "completed" and s["ranks"] == n
        x, v = final_field(tmp_path / f"n{n}")
        if ref is None:
            ref, ref_summary = (x, v), s
            continue
        assert np.array_equal(x, ref[0])
        rel = np.abs(v - ref[1]).max() / np.abs(ref[1]).max()
        print(f"{scene} {n} ranks: max relative difference to serial {rel:.2e}")
        assert rel <= 1e-10
        assert s["dofs"] == ref_summary["dofs"]
