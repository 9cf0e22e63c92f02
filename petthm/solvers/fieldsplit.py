"""Field splits of a problem's unknowns for PCFIELDSPLIT, the context that
petthm's Python preconditioners get from the run they serve, and the Python
PC that rebuilds the splits on the reduced systems of the VI Newton methods.

* ``SolverContext``: the problem, the SNES (its VI inactive set), and what
  is computed once per run in the problem's global numbering: the field
  index sets, the rigid-body modes, the contact pairs.  ``serve`` hands it to
  a PC; ``served_rows`` tells a PC which unknowns of the full system its
  operator's rows are.
* ``field_splits``: one index set per field, named by the field (the
  fieldsplit prefix ``-fieldsplit_u_...``), with the rigid-body modes of
  ``u`` composed as "nearnullspace" for GAMG (petsc-notes "Field split").
* ``VIFieldSplit``: ``-pc_type python -pc_python_type
  petthm.solvers.fieldsplit.VIFieldSplit``.  ``vinewtonrsls`` solves on the
  inactive set, which changes with the contact state; a PCFIELDSPLIT set up
  once would keep index sets of the wrong space (petsc-notes "Contact and
  SNES VI").
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from petthm import compat
from petthm.discretisation import probes
from petthm.errors import OPTION_ERRORS, InputError, petsc_option_errors
from petthm.solvers.nullspace import orthonormal_nullspace
from petthm.solvers.options import Proposals
from petthm.solvers.sweep import LowerSweep

#: the attribute of a PC through which ``solver.TimeStepper`` gives a Python
#: PC the ``SolverContext`` it serves (a weak reference)
SERVES = "petthm_context"
#: the attribute of a split's PC through which ``VIFieldSplit`` tells it
#: which unknowns of the full system its rows are: (context ref, rows, maps)
SPLIT = "petthm_split"


class SolverContext:
    """What petthm's Python preconditioners need from the run they serve:
    the problem, its SNES (the VI inactive set), and structures computed once
    per run in the problem's global numbering."""

    def __init__(self, problem, snes: PETSc.SNES | None = None, proposals=None):
        """``proposals``: the run's ``options.Proposals`` (the options a
        preconditioner proposes for its inner solvers go there)."""
        self.problem = problem
        self.proposals = proposals if proposals is not None else Proposals()
        self._warned: set[str] = set()
        self._snes = weakref.ref(snes) if snes is not None else None
        names, isets, _ = problem.dm.createFieldDecomposition()
        self.fields = {name: iset.getIndices().copy() for name, iset in zip(names, isets, strict=False)}
        self._contact = None
        self._rigid = None
        self._interp = False                      # not made yet (None: u is not P2)

    def warn_once(self, message: str) -> None:
        """Print a warning on rank 0, once per run."""
        if message not in self._warned:
            self._warned.add(message)
            PETSc.Sys.Print(f"petthm: warning: {message}")

    def rows(self, P: PETSc.Mat) -> np.ndarray:
        """The full-system unknowns of the operator's rows on this rank: the
        VI inactive set of ``vinewtonrsls`` when the operator is that reduced
        system, else all of them."""
        snes = self._snes() if self._snes is not None else None
        if snes is not None and snes.getType() == "vinewtonrsls" and \
                P.getSize()[0] != self.problem.X.getSize():
            return np.asarray(snes.getVIInactiveSet().getIndices(), dtype=compat.INT)
        r0, r1 = P.getOwnershipRange()
        return np.arange(r0, r1, dtype=compat.INT)

    def holds(self, field: str, rows: np.ndarray) -> bool:
        """Whether the full-system unknowns ``rows`` (this rank's) hold any
        unknown of ``field`` on any rank (collective)."""
        mine = np.isin(self.fields[field], rows) if field in self.fields else np.zeros(0, dtype=bool)
        return probes.global_count(self.problem.dm.comm, mine) > 0

    def contact(self):
        """The contact pairs (``contactpc.ContactStructure``), made once."""
        if self._contact is None:
            from petthm.solvers.glue import contact_structure
            self._contact = contact_structure(self.problem)
        return self._contact

    def rigid_modes(self) -> list[PETSc.Vec]:
        """Translations and rotations of the u unknowns as full-system vectors
        (zero on the other fields; components fixed by rollers are not
        unknowns and are absent), made once."""
        if self._rigid is None:
            self._rigid = _rigid_mode_vectors(self.problem)
        return self._rigid

    def lam_below_u(self) -> bool:
        """A contact traction of lower degree than u (the consistent
        pairing with P2 u): the glue then holds the vertices only."""
        disc = self.problem.disc
        names = [f.name for f in disc.fields]
        return "lam" in names and disc.field("lam").degree < disc.field("u").degree

    def p1_interpolation(self):
        """The P1 -> P2 interpolation of u (``pmg.p1_interpolation``), made
        once; None when u is not P2."""
        if self._interp is False:
            from petthm.solvers.pmg import p1_interpolation
            self._interp = p1_interpolation(self.problem)
        return self._interp

    def destroy(self) -> None:
        if self._interp:
            self._interp[0].destroy()
        self._interp = False
        if self._contact is not None:
            self._contact.destroy()
        for v in self._rigid or ():
            v.destroy()
        self._contact = self._rigid = None


def serve(pc: PETSc.PC, context: SolverContext) -> None:
    """Tell a Python PC which run it serves (kept on the PC: PETSc replaces
    the Python context whenever it reads the options; a weak reference, so
    that the PC does not keep its own SNES alive past PETSc's finalisation)."""
    pc.setAttr(SERVES, weakref.ref(context))


def served_rows(pc: PETSc.PC):
    """(context, rows, maps) of a Python PC: the run it serves, the
    full-system unknowns of its operator's rows on this rank, and the contact
    maps of that operator when the PC that made the split computed them
    (else None)."""
    split = pc.getAttr(SPLIT)
    if split is not None:
        ref, rows, maps = split
        context = ref()
    else:
        ref = pc.getAttr(SERVES)
        context = ref() if ref is not None else None
        rows = maps = None
    if context is None:
        raise RuntimeError("this preconditioner is set up by petthm's TimeStepper only")
    return context, rows if rows is not None else context.rows(pc.getOperators()[1]), maps


@dataclass
class Split:
    """One split of an operator: its name, its rows in the operator's
    numbering (``iset``) and the full-system unknowns they are (``rows``)."""
    name: str
    iset: PETSc.IS
    rows: np.ndarray


def field_splits(context: SolverContext, rows: np.ndarray | None = None, r0: int = 0) -> list[Split]:
    """One split per field of an operator whose rows on this rank are the
    full-system unknowns ``rows`` (sorted; default: all) and begin at row
    ``r0``; the rigid-body modes of ``u`` composed on its index set as
    "nearnullspace".  Fields without rows anywhere are left out."""
    comm = context.problem.dm.comm
    out = []
    for name, idx in context.fields.items():
        inside = idx if rows is None else idx[np.isin(idx, rows)]
        pos = inside if rows is None else np.searchsorted(rows, inside) + r0
        iset = PETSc.IS().createGeneral(pos.astype(compat.INT), comm=comm)
        if iset.getSize() == 0:
            continue
        if name == "u":
            iset.compose("nearnullspace", restricted_modes(context, inside))
        out.append(Split(name, iset, inside))
    return out


def restricted_modes(context: SolverContext, rows: np.ndarray) -> PETSc.NullSpace:
    """The rigid-body modes on the full-system unknowns ``rows`` (this
    rank's, u only), orthonormalised."""
    return orthonormal_nullspace(mode_vectors(context, rows), context.problem.dm.comm)


def mode_vectors(context: SolverContext, rows: np.ndarray) -> list[PETSc.Vec]:
    """The rigid-body modes on the full-system unknowns ``rows`` (this
    rank's, sorted, u only): new vectors in the numbering of those rows."""
    iset = PETSc.IS().createGeneral(np.asarray(rows, dtype=compat.INT), comm=context.problem.dm.comm)
    out = []
    for mode in context.rigid_modes():
        sub = mode.getSubVector(iset)
        out.append(sub.copy())
        mode.restoreSubVector(iset, sub)
    iset.destroy()
    return out


def _rigid_mode_vectors(problem) -> list[PETSc.Vec]:
    disc = problem.disc
    d = disc.mesh.dim
    dofs = disc.field_local_dofs("u")                            # (n, d) local
    x = disc.field_node_coordinates("u")
    x = x - x.mean(axis=0) if len(x) else x
    gidx = disc.global_index[dofs]
    own = disc._owned(gidx) & ~np.isin(dofs, problem.constraints.constrained_local())
    r0 = problem.X.getOwnershipRange()[0]
    comp = np.broadcast_to(np.arange(d), dofs.shape)[own]
    xs = np.broadcast_to(x[:, None, :], dofs.shape + (d,))[own]
    out = []
    for m in rigid_modes(comp, xs):
        v = problem.X.duplicate()
        v.set(0.0)
        v.getArray()[gidx[own] - r0] = m
        out.append(v)
    return out


def rigid_modes(comp: np.ndarray, x: np.ndarray) -> list[np.ndarray]:
    """Translations and rotations of displacement unknowns of components
    ``comp`` at points ``x`` (one row per unknown)."""
    d = x.shape[1]
    modes = [np.asarray(comp == k, dtype=float) for k in range(d)]
    for a, b in ([(0, 1)] if d == 2 else [(0, 1), (1, 2), (2, 0)]):    # rotation in the (a, b) plane
        modes.append(np.where(comp == a, -x[:, b], 0.0) + np.where(comp == b, x[:, a], 0.0))
    return modes


class VIFieldSplit:
    """Field split for the reduced systems of PETSc's VI Newton methods (and
    for any system: without bounds it splits the whole one).

    At every set-up an inner PCFIELDSPLIT is rebuilt: one split per field
    restricted to ``SNES.getVIInactiveSet()`` (all unknowns for
    ``vinewtonssls``), named by the field, the rigid-body modes on u.  The
    inner PC takes its options with the prefix ``vi_``
    (``-vi_pc_fieldsplit_type schur``, ``-vi_fieldsplit_u_pc_type gamg``, ...).

    ``-vi_groups NAME=F1+F2,NAME2=...`` merges fields into named splits
    (fields the scene does not have are skipped, empty groups dropped), so
    that one recipe serves u with lam alone and u with {lam, pf, Tf, Tm}:
    ``-vi_groups mech=u+lam,rest=pm+pf+Tm+Tf``.  Every split's PC learns
    which unknowns it holds (``served_rows``), so a split can be given
    ``contactpc.ContactNullspacePC``.

    Every split s after the mechanics (the first split that holds u,
    ``mechanics_split``) is preconditioned by an approximation of its Schur
    complement with respect to the mechanics
    (``split_block``; the "pmat" of its index set: the block of a
    multiplicative split, the preconditioner of the Schur complement with
    ``-vi_pc_fieldsplit_type schur -vi_pc_fieldsplit_schur_precondition
    user``): S_s = A_ss - A_s,lam G A_u,s when the mechanics split holds
    lam too (what its fields see of the contact when the glue carries their
    face loads; ``-vi_contact_schur faces|all|off``, ``contact_schur``), plus the model's
    preconditioner blocks (the fixed-stress term of Biot;
    ``-vi_fixed_stress 0`` leaves it out)."""

    def __init__(self):
        self.inner = self.sweep = None
        self._owned: list = []

    def setUp(self, pc):
        A, P = pc.getOperators()
        ref = pc.getAttr(SERVES)
        context = ref() if ref is not None else None
        if context is None:
            raise RuntimeError("VIFieldSplit is set up by petthm's TimeStepper only")
        # the objects of the last set-up that Python has let go of: on a parallel
        # communicator petsc4py keeps them in its garbage until this collective call
        PETSc.garbage_cleanup(pc.getComm())
        rows = context.rows(P)
        r0 = P.getOwnershipRange()[0]
        splits = self._grouped(field_splits(context, rows, r0), pc)
        self.reset(pc)
        self.inner = PETSc.PC().create(comm=pc.getComm())
        self.inner.setOptionsPrefix((pc.getOptionsPrefix() or "") + "vi_")
        self.inner.setOperators(A, P)
        self.inner.setType("fieldsplit")
        self.inner.setFieldSplitIS(*[(s.name, s.iset) for s in splits])
        first = mechanics_split(context, splits)
        maps = self._contact_maps(context, P, splits[first]) if first is not None else None
        # the splits' KSPs exist once their index sets are given (the Schur
        # type reports them only after its set-up: ask before the options make it one)
        for k, (split, ksp) in enumerate(zip(splits, self.inner.getFieldSplitSubKSP(), strict=False)):
            own_maps = maps if k == first else None
            ksp.getPC().setAttr(SPLIT, (weakref.ref(context), split.rows, own_maps))
        opts = PETSc.Options(self.inner.getOptionsPrefix())
        extra = context.problem.preconditioner_blocks() if opts.getBool("fixed_stress", True) else None
        schur = contact_schur(opts)
        glue = maps if schur != "off" else None
        faces = context.problem.face_load_blocks() if glue is not None and schur == "faces" else None
        after = splits[first + 1:] if first is not None else []
        for split in after:                                     # their preconditioning blocks
            Sp = split_block(P, split, rows, context, glue, extra, faces)
            if Sp is not None:
                split.iset.compose("pmat", Sp)
                self._owned.append(Sp)
        with petsc_option_errors(f"the options of the block recipe (-{self.inner.getOptionsPrefix()}*)",
                                 OPTION_ERRORS):
            self.inner.setFromOptions()          # the splits read theirs in the set-up
            lower = _lower_sweep(opts) and len(splits) > 2
            if lower:                            # the sweep below; PETSc sets up the splits only
                self.inner.setFieldSplitType(PETSc.PC.CompositeType.ADDITIVE)
            self.inner.setUp()
        if lower:
            self.sweep = LowerSweep(P, [s.iset for s in splits], self.inner.getFieldSplitSubKSP(),
                                    [s.name for s in splits])

    def _contact_maps(self, context, P, split):
        """The contact maps of the mechanics split when it holds lam too."""
        if not context.holds("lam", split.rows):
            return None
        from petthm.solvers.glue import glue_maps
        K = P.createSubMatrix(split.iset, split.iset)
        maps = glue_maps(K, context.contact(), split.rows)
        K.destroy()
        self._owned.append(maps)
        return maps

    @staticmethod
    def _grouped(splits: list[Split], pc) -> list[Split]:
        """The splits merged by ``-vi_groups`` (see the class docstring)."""
        text = PETSc.Options((pc.getOptionsPrefix() or "") + "vi_").getString("groups", "")
        if not text:
            return splits
        by_name = {s.name: s for s in splits}
        grouped = {f for item in text.split(",") for f in item.partition("=")[2].split("+")}
        missing = [n for n in by_name if n not in grouped]
        if missing:
            raise InputError(f"option -vi_groups = {text} leaves out the field(s) {', '.join(missing)}")
        out = []
        for item in text.split(","):
            name, _, members = item.partition("=")
            if not name or not members:
                raise InputError(f"option -vi_groups: '{item}' is not NAME=FIELD+FIELD...")
            parts = [by_name[f] for f in members.split("+") if f in by_name]
            if len(parts) == 1:
                out.append(Split(name, parts[0].iset, parts[0].rows))
            elif parts:
                idx = np.unique(np.concatenate([p.iset.getIndices() for p in parts])).astype(compat.INT)
                rows = np.unique(np.concatenate([p.rows for p in parts]))
                out.append(Split(name, PETSc.IS().createGeneral(idx, comm=pc.getComm()), rows))
        return out

    def reset(self, pc):
        if self.sweep is not None:
            self.sweep.destroy()
            self.sweep = None
        if self.inner is not None:
            self.inner.destroy()
            self.inner = None
        for obj in self._owned:
            obj.destroy()
        self._owned = []

    def apply(self, pc, x, y):
        if self.sweep is not None:
            self.sweep.apply(x, y)
        else:
            self.inner.apply(x, y)


CONTACT_SCHUR = {"faces": "faces", "1": "all", "true": "all", "all": "all", "off": "off", "0": "off",
                 "false": "off"}


def mechanics_split(context: SolverContext, splits: list[Split]) -> int | None:
    """The position of the first split that holds u (None without one).
    The splits after it are preconditioned by their Schur complements with
    respect to it (``split_block``); those before it are solved first
    without one: a field whose equation does not see u (the rock
    temperature: its thermal stress loads u, u does not enter its balance)
    placed before the mechanics makes that coupling exact in the
    multiplicative sweep (manual, solver guide, "Scene 3 at the default resolution")."""
    return next((k for k, s in enumerate(splits) if context.holds("u", s.rows)), None)


def _lower_sweep(opts: PETSc.Options) -> bool:
    """Whether the splits are swept by ``sweep.LowerSweep``: the
    multiplicative type (PCFIELDSPLIT's default) unless
    ``-vi_lower_sweep 0`` asks for PETSc's own sweep (the same
    preconditioner; it multiplies whole row blocks)."""
    kind = opts.getString("pc_fieldsplit_type", "multiplicative").lower()
    return kind == "multiplicative" and opts.getBool("lower_sweep", True)


def contact_schur(opts: PETSc.Options) -> str:
    """``-vi_contact_schur``: the load the contact-Schur term of ``split_block``
    takes: ``all`` (default: every term of the u rows, the rock's body
    loads of the wall nodes tied into the split too), ``faces`` (the
    fracture terms of the u rows alone), ``off`` (no term).  Measured
    (manual, solver guide): Scene 2 needs ``all`` (the thermal strain
    of the tied wall nodes: ``faces`` rejects 11 steps, as ``off`` does),
    the coupled MMS with the fracture closed needs ``faces`` (``all``
    rejects 3 of 7 steps)."""
    text = opts.getString("contact_schur", "all").lower()
    if text not in CONTACT_SCHUR:
        raise InputError(f"option -{opts.prefix}contact_schur = {text}: accepted faces, all, off")
    return CONTACT_SCHUR[text]


def split_block(P: PETSc.Mat, split: Split, rows: np.ndarray, context, maps=None,
                extra: PETSc.Mat | None = None, faces: PETSc.Mat | None = None) -> PETSc.Mat | None:
    """The preconditioning block of ``split`` when it comes after the
    mechanics split (see ``VIFieldSplit``): an approximation of its Schur
    complement A_ss - A_s,m K^-1 A_m,s with respect to the mechanics m,

        S = A_ss - A_s,lam G A_u,s  [- A_s,u' diag(A_u'u')^-1 A_u',s]  + E_ss

    * A_s,lam G A_u,s (with the contact ``maps`` of the {u, lam} split, G
      their lam-recovery map): the {u, lam} split answers a load on the
      fracture faces with the contact traction alone (the glue of
      ``contactpc``, the lumped contact of the closed nodes).  For a fluid
      pressure on a closed fracture this is the Schur complement, exact with
      lumped weights: lam changes by -p and u does not move, so the
      fracture storage gains the joint compliance d(ac)/d(lam) that the
      pressure rows see through lam (the fracture analogue of fixed stress).
      With ``-vi_contact_schur faces`` (``Problem.face_load_blocks``)
      A_u,s holds the fracture terms of the u rows alone, without the
      rock's body loads of the wall nodes tied into pf and Tf (Biot,
      thermal strain), which G takes for face loads (``contact_schur``);
    * A_s,u diag(A_uu)^-1 A_u,s: what the displacement gives of the rest
      (the opening of the open fracture faces under the fluid pressure),
      with the elasticity by its diagonal ("selfp"); not where the model
      has a block of its own for the field;
    * E (``extra``, full-system numbering): the model's preconditioner
      blocks (``Problem.preconditioner_blocks``: the fixed-stress term).

    None when no term applies (the block stays A_ss)."""
    comm = P.getComm()
    r0 = P.getOwnershipRange()[0]
    has_extra = extra is not None and probes.global_count(comm, np.isin(split.rows, _rows_of(extra))) > 0

    def held(*fields):
        mine = np.zeros(len(rows), dtype=bool)
        for field in fields:
            mine |= np.isin(rows, context.fields.get(field, ()))
        return mine

    def positions(*fields):
        return PETSc.IS().createGeneral((np.flatnonzero(held(*fields)) + r0).astype(compat.INT), comm=comm)
    iu = positions("u")
    S = P.createSubMatrix(split.iset, split.iset)
    Aus = P.createSubMatrix(iu, split.iset)
    terms = []
    if maps is not None:
        ilam = positions("lam", "tau")                        # the contact rows of the glue maps
        Asl = P.createSubMatrix(split.iset, ilam)
        G = maps.recovery(coupled=True)
        if faces is not None:                               # the faces' loads alone (full numbering)
            ius = [PETSc.IS().createGeneral(r.astype(compat.INT), comm=comm)
                   for r in (rows[held("u")], split.rows)]
            Afs = faces.createSubMatrix(*ius)
            GA = G.matMult(Afs)
            for obj in (*ius, Afs):
                obj.destroy()
        else:
            GA = G.matMult(Aus)
        terms.append((-1.0, Asl.matMult(GA)))
        for obj in (ilam, Asl, G, GA):
            obj.destroy()
    if has_extra:
        full = PETSc.IS().createGeneral(split.rows.astype(compat.INT), comm=comm)
        terms.append((1.0, extra.createSubMatrix(full, full)))
        full.destroy()
    else:
        Asu = P.createSubMatrix(split.iset, iu)
        diag = P.getDiagonal()                               # diag(A_uu): no copy of the u block
        sub = diag.getSubVector(iu)
        dinv = sub.copy()
        diag.restoreSubVector(iu, sub)
        dinv.reciprocal()
        Aus.diagonalScale(L=dinv)
        terms.append((-1.0, Asu.matMult(Aus)))
        for obj in (Asu, diag, dinv):
            obj.destroy()
    for a, T in terms:
        S.axpy(a, T, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        T.destroy()
    iu.destroy()
    Aus.destroy()
    return S


def _rows_of(M: PETSc.Mat) -> np.ndarray:
    """The owned rows of M that hold an entry."""
    ai = M.getValuesCSR()[0]
    return np.flatnonzero(np.diff(ai)) + M.getOwnershipRange()[0]
