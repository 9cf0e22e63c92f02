"""The reference simplices (manual: "Discretisation"): the segment
(0),(1), the triangle (0,0),(1,0),(0,1) and the tetrahedron
(0,0,0),(1,0,0),(0,1,0),(0,0,1); their vertices, their edges in VTK/XDMF
order (``Triangle_6``, ``Tetrahedron_10`` number their edge nodes in this
order) and their volumes.  The mesh numbers the edges of its cells in this
order; the elements (``petthm.discretisation.fe``) place their edge nodes on them."""
from __future__ import annotations

import numpy as np

EDGES = {
    1: np.array([[0, 1]]),
    2: np.array([[0, 1], [1, 2], [0, 2]]),
    3: np.array([[0, 1], [1, 2], [0, 2], [0, 3], [1, 3], [2, 3]]),
}
REFERENCE_VERTICES = {d: np.vstack([np.zeros(d), np.eye(d)]) for d in (1, 2, 3)}
REFERENCE_VOLUME = {0: 1.0, 1: 1.0, 2: 0.5, 3: 1.0 / 6.0}

__all__ = ["EDGES", "REFERENCE_VERTICES", "REFERENCE_VOLUME"]
