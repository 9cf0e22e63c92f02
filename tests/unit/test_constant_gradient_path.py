"""The Jacobian's gradient terms of P1 functions summed over the cell first
(``Assembler._constant_gradient_terms``) against the reference-tensor path
that integrates every term point by point (docs/performance/index.md, "P1
gradient terms summed over the cell")."""
import numpy as np
import pytest

from petthm.discretisation.assembly import Assembler


@pytest.mark.parametrize("scene,opts", [
    ("coupled_mms", dict(thm_fe_degree=1, thm_mesh_size=0.25)),                    # every coupling, 2D
    ("coupled_mms", dict(thm_fe_degree=1, thm_mesh_size=0.5, thm_coupled_mms_dim=3)),
    ("inclined_penny", dict(thm_fe_degree=2, thm_scene3_fracture_size=50, thm_scene3_well_size=15,
                            thm_mesh_size=300)),                                  # P2 u, P1 flow and heat
    ("lauwerier", dict(thm_fe_degree=1, thm_lauwerier_fracture_size=10.0)),      # a fracture region
])
def test_p1_gradient_terms_summed_first_equal_the_pointwise_path(tmp_path, monkeypatch, scene, opts):
    from conftest import build_problem
    p = build_problem(tmp_path, scene, **opts)
    rng = np.random.default_rng(5)
    xl, xdl = (a.copy() for a in p.local_arrays(p.X, 0.0))
    xl += rng.standard_normal(xl.size) * 0.05
    xdl = rng.standard_normal(xdl.size) * 1e-2
    used = []
    summed_first = Assembler._constant_gradient_terms

    def spy(self, jb, ctx, cells, fast):
        used.append((jb.test, jb.trial))
        return summed_first(self, jb, ctx, cells, fast)
    monkeypatch.setattr(Assembler, "_constant_gradient_terms", spy)
    for region, a in p.assemblers.items():
        fast = a.jacobian_values(xl, xdl, 0.3, 2.0)
        monkeypatch.setattr(Assembler, "CONSTANT_GRADIENT_PATH", False)
        pointwise = a.jacobian_values(xl, xdl, 0.3, 2.0)
        monkeypatch.setattr(Assembler, "CONSTANT_GRADIENT_PATH", True)
        scale, diff = np.abs(pointwise).max(), np.abs(fast - pointwise).max()
        print(scene, region, "entries", fast.size, "largest difference", diff, "of", scale)
        assert diff <= 1e-12 * scale
    assert used, "no block took the summed-first path"
