"""Every difference between the supported PETSc/petsc4py versions (3.18-3.26).

petthm calls PETSc through petsc4py.  A few C functions that it needs are not
wrapped by every petsc4py release (COO matrix assembly before 3.24, DMPlex
cone arrays); those are reached through a small ctypes bridge to the
``libpetsc`` that petsc4py has already loaded into the process, so that the
very same library (and its integer width) is used.  Nothing outside this
module may test the PETSc version.
"""
from __future__ import annotations

import ctypes
import functools

import numpy as np
from petsc4py import PETSc

MIN_VERSION = (3, 18, 0)
VERSION = tuple(PETSc.Sys.getVersion())

if VERSION < MIN_VERSION:  # pragma: no cover - checked at import on old installs
    raise ImportError(
        f"petthm needs PETSc >= {'.'.join(map(str, MIN_VERSION))}, "
        f"found {'.'.join(map(str, VERSION))}")

INT = np.dtype(PETSc.IntType)
SCALAR = np.dtype(PETSc.ScalarType)
if np.float64 != SCALAR:  # pragma: no cover
    raise ImportError("petthm needs a real, double-precision PETSc build")


#: SNES's reason for a NaN function norm (renamed DIVERGED_FUNCTION_NANORINF in PETSc 3.23)
SNES_DIVERGED_NAN = getattr(PETSc.SNES.ConvergedReason, "DIVERGED_FNORM_NAN", None) \
    or PETSc.SNES.ConvergedReason.DIVERGED_FUNCTION_NANORINF


#: GAMG's option for the number of levels it coarsens aggressively (graph squaring in
#: PETSc 3.18, renamed ``pc_gamg_aggressive_coarsening`` in 3.19, MIS-2 by default since)
GAMG_AGGRESSIVE_LEVELS = "pc_gamg_square_graph" if VERSION < (3, 19) else "pc_gamg_aggressive_coarsening"


def version_string() -> str:
    """'3.18.5'-style PETSc version of the loaded library."""
    return ".".join(str(v) for v in VERSION)


# --------------------------------------------------------------------------
# ctypes bridge
# --------------------------------------------------------------------------
@functools.cache
def _lib() -> ctypes.CDLL:
    """The libpetsc already mapped into this process by petsc4py."""
    with open("/proc/self/maps") as maps:
        for line in maps:
            path = line.split()[-1]
            name = path.rsplit("/", 1)[-1]
            if name.startswith("libpetsc") and ".so" in name:
                return ctypes.CDLL(path)
    raise ImportError("cannot locate the libpetsc loaded by petsc4py")  # pragma: no cover


_c_int_p = np.ctypeslib.ndpointer(dtype=INT, flags="C_CONTIGUOUS")
_c_real_p = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
_c_petscint = ctypes.c_int64 if INT.itemsize == 8 else ctypes.c_int32


def _check(ierr: int, fname: str) -> None:
    if ierr:
        raise RuntimeError(f"PETSc error {ierr} in {fname}")


def _cfunc(name: str, *argtypes):
    fn = getattr(_lib(), name)
    fn.restype = ctypes.c_int
    fn.argtypes = list(argtypes)
    return fn


def snes_lag_preconditioner(snes: PETSc.SNES, lag: int, persists: bool | None = None) -> None:
    """SNESSetLagPreconditioner (-1: never rebuild, -2: rebuild once, then -1)
    and SNESSetLagPreconditionerPersists (not wrapped by petsc4py 3.18-3.26)."""
    fn = _cfunc("SNESSetLagPreconditioner", ctypes.c_void_p, _c_petscint)
    _check(fn(snes.handle, lag), "SNESSetLagPreconditioner")
    if persists is not None:
        fn = _cfunc("SNESSetLagPreconditionerPersists", ctypes.c_void_p, ctypes.c_int)
        _check(fn(snes.handle, int(bool(persists))), "SNESSetLagPreconditionerPersists")


def set_jacobian_domain_error(snes: PETSc.SNES) -> None:
    """SNESSetJacobianDomainError (not in petsc4py 3.18): the Jacobian cannot
    be evaluated at this state; Newton stops (DIVERGED_JACOBIAN_DOMAIN) and
    the time step is tried again, smaller."""
    fn = _cfunc("SNESSetJacobianDomainError", ctypes.c_void_p)
    _check(fn(snes.handle), "SNESSetJacobianDomainError")


def ptap(A: PETSc.Mat, P: PETSc.Mat) -> PETSc.Mat:
    """P^T A P (petsc4py 3.18: ``Mat.PtAP``; renamed ``Mat.ptap`` later)."""
    fn = getattr(A, "ptap", None) or A.PtAP
    return fn(P)


# --------------------------------------------------------------------------
# Sections
# --------------------------------------------------------------------------
def set_local_section(dm: PETSc.DM, section: PETSc.Section) -> None:
    """DMSetLocalSection (named setSection in petsc4py < 3.20)."""
    if hasattr(dm, "setLocalSection"):
        dm.setLocalSection(section)
    else:
        dm.setSection(section)


def get_local_section(dm):
    """DMGetLocalSection (named getSection in petsc4py < 3.20)."""
    return dm.getLocalSection() if hasattr(dm, "getLocalSection") else dm.getSection()


# --------------------------------------------------------------------------
# COO assembly
# --------------------------------------------------------------------------
_NATIVE_COO = hasattr(PETSc.Mat, "setPreallocationCOO")


def coo_matrix(dm: PETSc.DM, rows: np.ndarray, cols: np.ndarray, copy: bool = True) -> PETSc.Mat:
    """The DM's matrix (sizes, type, local-to-global map) preallocated from the
    COO pattern alone: DMCreateMatrix's own preallocation, which
    MatSetPreallocationCOO replaces anyway, is skipped
    (DMSetMatrixPreallocateSkip; it cost 2.5-3 s per matrix at 1e4 P2
    tetrahedra, more than ten Jacobian assemblies).  ``copy``: see
    ``coo_preallocate``."""
    skip = _cfunc("DMSetMatrixPreallocateSkip", ctypes.c_void_p, ctypes.c_int)
    _check(skip(dm.handle, 1), "DMSetMatrixPreallocateSkip")
    try:
        mat = dm.createMat()
    finally:
        _check(skip(dm.handle, 0), "DMSetMatrixPreallocateSkip")
    coo_preallocate(mat, rows, cols, copy)
    return mat


def coo_preallocate(mat: PETSc.Mat, rows: np.ndarray, cols: np.ndarray, copy: bool = True) -> None:
    """MatSetPreallocationCOO with global indices (negative ones are ignored).
    PETSc may overwrite the index arrays: they are copied unless ``copy`` is
    False (the caller hands over arrays it does not use again)."""
    rows = np.ascontiguousarray(rows, dtype=INT)
    cols = np.ascontiguousarray(cols, dtype=INT)
    if copy:
        rows, cols = rows.copy(), cols.copy()
    if _NATIVE_COO:
        mat.setPreallocationCOO(rows, cols)
        return
    fn = _cfunc("MatSetPreallocationCOO", ctypes.c_void_p, ctypes.c_int64,
                _c_int_p, _c_int_p)
    _check(fn(mat.handle, rows.size, rows, cols), "MatSetPreallocationCOO")


def coo_set_values(mat: PETSc.Mat, values: np.ndarray) -> None:
    """MatSetValuesCOO(..., INSERT_VALUES): repeated entries are summed."""
    values = np.ascontiguousarray(values, dtype=np.float64)
    if _NATIVE_COO:
        mat.setValuesCOO(values, addv=PETSc.InsertMode.INSERT_VALUES)
        return
    fn = _cfunc("MatSetValuesCOO", ctypes.c_void_p, _c_real_p, ctypes.c_int)
    _check(fn(mat.handle, values, int(PETSc.InsertMode.INSERT_VALUES)),
           "MatSetValuesCOO")


# --------------------------------------------------------------------------
# DMPlex topology arrays
# --------------------------------------------------------------------------
def plex_cone_array(dm: PETSc.DMPlex, pstart: int, pend: int, size: int) -> np.ndarray:
    """Cones of the points [pstart, pend) as an (n, size) array.

    All points of the range must have cone size ``size``; uses
    DMPlexGetCones/DMPlexGetConeSection so that no Python loop over points is
    needed.
    """
    n = pend - pstart
    if n == 0:
        return np.zeros((0, size), dtype=INT)
    sec = ctypes.c_void_p()
    _check(_cfunc("DMPlexGetConeSection", ctypes.c_void_p,
                  ctypes.POINTER(ctypes.c_void_p))(dm.handle, ctypes.byref(sec)),
           "DMPlexGetConeSection")
    cones = ctypes.POINTER(_c_petscint)()
    _check(_cfunc("DMPlexGetCones", ctypes.c_void_p,
                  ctypes.POINTER(ctypes.POINTER(_c_petscint)))(dm.handle, ctypes.byref(cones)),
           "DMPlexGetCones")
    get_off = _cfunc("PetscSectionGetOffset", ctypes.c_void_p, _c_petscint,
                     ctypes.POINTER(_c_petscint))
    first, last = _c_petscint(), _c_petscint()
    _check(get_off(sec, pstart, ctypes.byref(first)), "PetscSectionGetOffset")
    _check(get_off(sec, pend - 1, ctypes.byref(last)), "PetscSectionGetOffset")
    if last.value - first.value != (n - 1) * size or dm.getConeSize(pend - 1) != size:
        raise RuntimeError("DMPlex cone storage is not contiguous for this stratum")
    total = first.value + n * size
    arr = np.ctypeslib.as_array(cones, shape=(total,))
    return arr[first.value:total].reshape(n, size).copy()


def lgmap_indices(dm: PETSc.DM) -> np.ndarray:
    """Global index of every local dof (constrained dofs are negative)."""
    return np.asarray(dm.getLGMap().getIndices(), dtype=INT)


def unused_options() -> list[str]:
    """Names (without '-') of options in the database that nothing has queried."""
    n = _c_petscint()
    names = ctypes.POINTER(ctypes.c_char_p)()
    values = ctypes.POINTER(ctypes.c_char_p)()
    fn = _cfunc("PetscOptionsLeftGet", ctypes.c_void_p, ctypes.POINTER(_c_petscint),
                ctypes.POINTER(ctypes.POINTER(ctypes.c_char_p)),
                ctypes.POINTER(ctypes.POINTER(ctypes.c_char_p)))
    _check(fn(None, ctypes.byref(n), ctypes.byref(names), ctypes.byref(values)), "PetscOptionsLeftGet")
    out = [names[i].decode() for i in range(n.value)]
    restore = _cfunc("PetscOptionsLeftRestore", ctypes.c_void_p, ctypes.POINTER(_c_petscint),
                     ctypes.POINTER(ctypes.POINTER(ctypes.c_char_p)),
                     ctypes.POINTER(ctypes.POINTER(ctypes.c_char_p)))
    _check(restore(None, ctypes.byref(n), ctypes.byref(names), ctypes.byref(values)),
           "PetscOptionsLeftRestore")
    return [s[1:] if s.startswith("-") else s for s in out]


# --------------------------------------------------------------------------
# Cohesive cells (not wrapped by petsc4py, or wrapped with a varying signature)
# --------------------------------------------------------------------------
_VP = ctypes.c_void_p


@functools.cache
def _capsule(name: str):
    """A petsc4py C-API constructor, e.g. PyPetscDM_New(DM) -> petsc4py object."""
    cap = PETSc.__pyx_capi__[name]
    api = ctypes.pythonapi
    api.PyCapsule_GetName.restype = ctypes.c_char_p
    api.PyCapsule_GetName.argtypes = [ctypes.py_object]
    api.PyCapsule_GetPointer.restype = _VP
    api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
    ptr = api.PyCapsule_GetPointer(cap, api.PyCapsule_GetName(cap))
    return ctypes.PYFUNCTYPE(ctypes.py_object, _VP)(ptr)


def _adopt(handle: int, kind: str):
    """Wrap a C object we own as a petsc4py object (which takes its own reference)."""
    obj = _capsule(f"PyPetsc{kind}_New")(handle)
    _check(_cfunc("PetscObjectDereference", _VP)(handle), "PetscObjectDereference")
    return obj


def create_submesh(dm: PETSc.DMPlex, label: PETSc.DMLabel, value: int) -> PETSc.DMPlex:
    """DMPlexCreateSubmesh(dm, label, value, markedFaces=TRUE)."""
    out = _VP()
    fn = _cfunc("DMPlexCreateSubmesh", _VP, _VP, _c_petscint, ctypes.c_int, ctypes.POINTER(_VP))
    _check(fn(dm.handle, label.handle, value, 1, ctypes.byref(out)), "DMPlexCreateSubmesh")
    return _adopt(out.value, "DM")


def subpoint_label(subdm: PETSc.DMPlex) -> PETSc.DMLabel:
    """A copy of the submesh's subpoint map (value = depth of each parent point)."""
    out = _VP()
    _check(_cfunc("DMPlexGetSubpointMap", _VP, ctypes.POINTER(_VP))(subdm.handle, ctypes.byref(out)),
           "DMPlexGetSubpointMap")
    return _capsule("PyPetscDMLabel_New")(out.value).duplicate()   # borrowed: New() takes a ref


def label_cohesive_complete(dm, label, tip, flip: bool, subdm) -> None:
    """DMPlexLabelCohesiveComplete; a NULL boundary label when ``tip`` is empty
    (an empty label segfaults in PETSc 3.18 and petsc4py refuses None)."""
    if tip is not None and tip.getStratumSize(1) > 0:
        dm.labelCohesiveComplete(label, tip, 1, flip, subdm)
        return
    if (3, 22) <= VERSION < (3, 26):
        fn = _cfunc("DMPlexLabelCohesiveComplete", _VP, _VP, _VP, _c_petscint, ctypes.c_int,
                    ctypes.c_int, _VP)
        ierr = fn(dm.handle, label.handle, None, 1, int(flip), 0, subdm.handle)
    else:
        fn = _cfunc("DMPlexLabelCohesiveComplete", _VP, _VP, _VP, _c_petscint, ctypes.c_int, _VP)
        ierr = fn(dm.handle, label.handle, None, 1, int(flip), subdm.handle)
    _check(ierr, "DMPlexLabelCohesiveComplete")


def construct_cohesive_cells(dm: PETSc.DMPlex, label: PETSc.DMLabel) -> PETSc.DMPlex:
    """DMPlexConstructCohesiveCells(dm, label, NULL): the split mesh."""
    out = _VP()
    fn = _cfunc("DMPlexConstructCohesiveCells", _VP, _VP, _VP, ctypes.POINTER(_VP))
    _check(fn(dm.handle, label.handle, None, ctypes.byref(out)), "DMPlexConstructCohesiveCells")
    return _adopt(out.value, "DM")


def simplex_range(dm: PETSc.DMPlex, height: int) -> tuple[int, int]:
    """Points of a height stratum that are not hybrid (cohesive/prism-tensor) points."""
    a, b = _c_petscint(), _c_petscint()
    fn = _cfunc("DMPlexGetSimplexOrBoxCells", _VP, _c_petscint, ctypes.POINTER(_c_petscint),
                ctypes.POINTER(_c_petscint))
    _check(fn(dm.handle, height, ctypes.byref(a), ctypes.byref(b)), "DMPlexGetSimplexOrBoxCells")
    return a.value, b.value


def plex_checks(dm: PETSc.DMPlex) -> dict[str, int]:
    """DMPlexCheck{Symmetry,Skeleton,Faces,Geometry,PointSF,InterfaceCones}: 0 = pass."""
    out = {
        "symmetry": _cfunc("DMPlexCheckSymmetry", _VP)(dm.handle),
        "skeleton": _cfunc("DMPlexCheckSkeleton", _VP, _c_petscint)(dm.handle, 0),
        "faces": _cfunc("DMPlexCheckFaces", _VP, _c_petscint)(dm.handle, 0),
        "geometry": _cfunc("DMPlexCheckGeometry", _VP)(dm.handle),
        "interface_cones": _cfunc("DMPlexCheckInterfaceCones", _VP)(dm.handle),
    }
    if VERSION >= (3, 17):
        out["point_sf"] = _cfunc("DMPlexCheckPointSF", _VP, _VP, ctypes.c_int)(dm.handle, None, 0)
    return out


def create_section(dm, labels, num_comp, num_dof, bc_field, bc_comps, bc_points) -> PETSc.Section:
    """DMPlexCreateSection; ``labels`` (one per field, or None) restrict each
    field to the points with label value 1 (petsc4py does not pass labels)."""
    if all(lab is None for lab in labels):
        return dm.createSection(num_comp, num_dof, bc_field or None, bc_comps or None,
                                bc_points or None)
    nf = len(num_comp)
    lab_arr = (_VP * nf)(*[None if lab is None else lab.handle for lab in labels])
    comp = np.ascontiguousarray(num_comp, dtype=INT)
    dof = np.ascontiguousarray(num_dof, dtype=INT)
    nbc = len(bc_field)
    bcf = np.ascontiguousarray(bc_field, dtype=INT) if nbc else np.zeros(1, dtype=INT)
    bcc = (_VP * max(nbc, 1))(*[i.handle for i in bc_comps])
    bcp = (_VP * max(nbc, 1))(*[i.handle for i in bc_points])
    out = _VP()
    fn = _cfunc("DMPlexCreateSection", _VP, _VP, _c_int_p, _c_int_p, _c_petscint, _c_int_p,
                _VP, _VP, _VP, ctypes.POINTER(_VP))
    _check(fn(dm.handle, ctypes.cast(lab_arr, _VP), comp, dof, nbc, bcf,
              ctypes.cast(bcc, _VP), ctypes.cast(bcp, _VP), None, ctypes.byref(out)),
           "DMPlexCreateSection")
    return _adopt(out.value, "Section")
