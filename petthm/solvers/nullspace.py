"""Near null spaces for the multigrid of the elasticity blocks: a
``MatNullSpace`` of given vectors (the rigid-body modes), orthonormalised."""
from __future__ import annotations

from petsc4py import PETSc


def orthonormal_nullspace(vecs: list, comm) -> PETSc.NullSpace:
    """A MatNullSpace of the vectors, orthonormalised (modified Gram-Schmidt;
    dependent ones dropped)."""
    out = []
    for v in vecs:
        for w in out:
            v.axpy(-v.dot(w), w)
        nv = v.norm()
        if nv > 1e-12:
            v.scale(1.0 / nv)
            out.append(v)
    return PETSc.NullSpace().create(vectors=out, comm=comm)


__all__ = ["orthonormal_nullspace"]
