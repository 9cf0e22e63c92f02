"""``sweep.LowerSweep``: the block Gauss-Seidel of ``VIFieldSplit`` over
the lower blocks only is PETSc's multiplicative PCFIELDSPLIT to round-off."""
import numpy as np
from petsc4py import PETSc

from petthm.solvers.sweep import LowerSweep


def _matrix(n: int, seed: int = 3) -> PETSc.Mat:
    """A non-symmetric, diagonally dominant sparse matrix."""
    rng = np.random.default_rng(seed)
    dense = np.where(rng.random((n, n)) < 0.3, rng.standard_normal((n, n)), 0.0)
    dense += np.diag(np.abs(dense).sum(axis=1) + 1.0)
    A = PETSc.Mat().createAIJ((n, n), comm=PETSc.COMM_SELF)
    A.setUp()
    rows, cols = np.nonzero(dense)
    for i, j in zip(rows, cols, strict=False):
        A.setValue(int(i), int(j), dense[i, j])
    A.assemble()
    return A


def _fieldsplit(A: PETSc.Mat, isets: list, kind) -> PETSc.PC:
    pc = PETSc.PC().create(comm=PETSc.COMM_SELF)
    pc.setOperators(A, A)
    pc.setType("fieldsplit")
    pc.setFieldSplitIS(*[(f"s{k}", s) for k, s in enumerate(isets)])
    pc.setFieldSplitType(kind)
    pc.setUp()
    for ksp in pc.getFieldSplitSubKSP():
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
    pc.setUp()
    return pc


def test_the_lower_sweep_is_petsc_multiplicative_fieldsplit():
    n = 40
    A = _matrix(n)
    order = np.random.default_rng(5).permutation(n)
    isets = [PETSc.IS().createGeneral(np.sort(part).astype(PETSc.IntType), comm=PETSc.COMM_SELF)
             for part in np.array_split(order, 4)]             # four interleaved splits
    Comp = PETSc.PC.CompositeType
    x = A.createVecRight()
    x.setArray(np.random.default_rng(7).standard_normal(n))
    out = {}
    for name, kind in (("petsc", Comp.MULTIPLICATIVE), ("additive", Comp.ADDITIVE)):
        pc = _fieldsplit(A, isets, kind)
        out[name] = x.duplicate()
        pc.apply(x, out[name])
    pc = _fieldsplit(A, isets, Comp.ADDITIVE)                  # the splits' solvers only
    sweep = LowerSweep(A, isets, pc.getFieldSplitSubKSP(), [f"s{k}" for k in range(4)])
    out["lower"] = x.duplicate()
    sweep.apply(x, out["lower"])
    a, b, c = (out[k].getArray() for k in ("lower", "petsc", "additive"))
    print("lower vs PETSc", np.abs(a - b).max(), "additive vs PETSc", np.abs(c - b).max())
    assert np.abs(a - b).max() <= 1e-13 * np.abs(b).max()
    assert np.abs(c - b).max() >= 1e-2 * np.abs(b).max()         # control: the sweep matters here
    sweep.destroy()
