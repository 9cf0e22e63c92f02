"""``scripts/scene3_flow_split.py``'s P1 gradients and measures: exact for a
linear field on tetrahedra, and its tangential part on triangles in 3D."""
import os
import sys

import numpy as np

from conftest import ROOT

sys.path.insert(0, os.path.join(ROOT, "scripts"))
from scene3_flow_split import p1_gradients  # noqa: E402


def test_p1_gradients_and_measures_of_simplices():
    rng = np.random.default_rng(3)
    g = np.array([0.3, -1.2, 2.0])
    X = rng.standard_normal((40, 3))
    tets = np.array([rng.choice(40, 4, replace=False) for _ in range(25)])
    grad, vol, centre = p1_gradients(X, tets, X @ g + 5.0)
    assert np.allclose(grad, g, atol=1e-9 * np.abs(g).max())
    P = X[tets]
    assert np.allclose(vol, np.abs(np.linalg.det(P[:, 1:] - P[:, :1])) / 6.0)
    assert np.allclose(centre, P.mean(axis=1))
    tris = tets[:, :3]
    grad, area, _ = p1_gradients(X, tris, X @ g)
    T = X[tris]
    n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    assert np.allclose(area, 0.5 * np.linalg.norm(n, axis=1))
    n /= np.linalg.norm(n, axis=1)[:, None]
    tangential = g - (n @ g)[:, None] * n
    assert np.allclose(grad, tangential, atol=1e-8)
    assert not np.allclose(grad, g, atol=1e-3)          # negative control: the normal part is gone
