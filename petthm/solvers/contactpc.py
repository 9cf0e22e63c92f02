"""A null-space preconditioner for frictionless contact: the {u, lam} block

    K = [ A  C ]      A: elasticity (u rows), C: the face loads of lam,
        [ B  D ]      B: the weak opening of the closed nodes (lam rows),
                      D: 0 on closed rows (the semismooth row of an open
                      node of ``vinewtonssls`` is nearly lam = 0 instead)

of the VI reduced system (theory manual, "Contact and friction"; kernels/contact.py).

A closed ("glued") node i holds the normal opening at zero: the constraint
glues the normal displacement of its two copies u+_i, u-_i.  With the pair
matrix P (column i: +n_i on the components of u+_i, -n_i on those of u-_i)
and the lumped (nodal) weights b = B P 1 and c = C^T P 1 of the weak
opening and of the face load, the preconditioner solves

    1. u_p = P (r_lam / b): the normal jump the lam rows ask for, split
       evenly between the faces;
    2. A_Z v = Z^T (r_u - A u_p), with Z the orthonormal basis of the
       displacements that keep every glued node glued (the tangential
       components of each copy and one shared normal component): A_Z =
       Z^T A Z is the elasticity of the body glued along its closed
       fracture parts, for algebraic multigrid (GAMG, with the rigid-body
       modes Z^T r) like any elasticity matrix; u = Z v + u_p;
    3. lam = (P^T (r_u - A u)) / c: the normal force the glue carries.

With B and C exact nodal (lumped) operators and an exact A_Z solve this is
the null-space method, an exact solve; with the consistent weak opening it
is spectrally equivalent to it with constants independent of the mesh
(lumped against consistent mass), so the outer Krylov count does not grow
under refinement.  Rows of lam that do not couple to u (an open node on the
full space of ``vinewtonssls``) are solved by their diagonal and not glued.

With Coulomb friction the block has the rows of the tangential traction
tau too (kernels/friction.py): a sticking node's tau rows glue the
tangential jump as lam glues the normal one (a closed sticking node is
glued whole), a slipping node's are rotated to its slip direction and
eliminated (``nodeblocks.slip_rotation``, ``nodeblocks.block_inverse``;
manual, solver guide "Friction").

Everything is a parallel PETSc matrix or vector operation (``glue``: the
pairs, normals, weights and Z).  The lam-recovery map G = diag(1/c) P^T
also gives the Schur complement of the flow and heat fields
(``fieldsplit.VIFieldSplit``): a fluid pressure on a closed fracture is
carried by the glue (lam changes by -p, u does not move).
"""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from petthm import compat
from petthm.errors import InputError
from petthm.solvers import pmg
from petthm.solvers.fieldsplit import mode_vectors, served_rows
from petthm.solvers.glue import glue_maps, glued_basis
from petthm.solvers.nodeblocks import block_inverse
from petthm.solvers.nullspace import orthonormal_nullspace

#: smoothing steps per multigrid level of the glued elasticity (default)
SMOOTHING_STEPS = 3

class ContactNullspacePC:
    """``-pc_type python -pc_python_type petthm.solvers.contactpc.ContactNullspacePC``
    for the {u, lam} block of a contact scene (see the module docstring): the
    whole system of a scene with u and lam only, or the {u, lam} split of
    ``fieldsplit.VIFieldSplit`` (a split with u alone, in a scene without
    contact, is solved by the inner solve with u's rigid-body modes).  The
    glued elasticity solve A_Z takes the options prefix ``<prefix>contact_``
    (default: one GAMG V-cycle with the glued body's rigid-body modes:
    ``-contact_ksp_type preonly -contact_pc_type gamg``)."""

    def __init__(self):
        self.maps = self.Z = self.ksp = self._coarse = None
        self.B = self.C = self.D = self.e_inv = self.A_pt = self.pt_A = None
        self._own_maps = False
        self._work: dict = {}

    def setUp(self, pc):
        _, K = pc.getOperators()
        context, rows, maps = served_rows(pc)
        self._release()
        comm = K.getComm()
        PETSc.garbage_cleanup(comm)              # see VIFieldSplit.setUp
        if maps is None and not context.holds("lam", rows):
            self._set_inner(pc, K, context, rows)                # u alone: its elasticity
            return
        if context.lam_below_u():
            context.warn_once("with P2 u and a P1 contact traction (-thm_contact_pairing consistent) "
                              "the glue holds only the fracture's vertices: the contact preconditioner is "
                              "approximate and may fail on a closed fracture that cuts the domain")
        self._own_maps = maps is None
        self.maps = glue_maps(K, context.contact(), rows) if maps is None else maps
        A = K.createSubMatrix(self.maps.iu, self.maps.iu)
        self._eliminate(K, A)
        self._contact_products(A)
        self.Z = glued_basis(self.maps, A)
        AZ = compat.ptap(A, self.Z)
        self._set_inner(pc, AZ, context, self.maps.u_full, self.Z)
        AZ.destroy()
        self._work = {"up": A.createVecLeft(), "t": A.createVecLeft(), "u": A.createVecLeft(),
                      "ru": A.createVecLeft(),
                      "zr": self.Z.createVecRight(), "v": self.Z.createVecRight(),
                      "s": self.maps.b.duplicate(), "lam": self.maps.b.duplicate(),
                      "xl": self.maps.b.duplicate()}
        A.destroy()                              # the apply needs only A P^T and P A

    def _eliminate(self, K, A):
        """Eliminate the contact rows the glue does not hold (open nodes, the
        semismooth rows in transition of ``vinewtonssls``, the tau rows of
        slipping nodes) exactly: with D the contact rows' own block (per
        node: lam, tau and their coupling), r_E = D_EE x_E + D_EG x_G + B_E u
        gives x_E = D_EE^-1 (r_E - D_EG x_G - B_E u), so the elasticity
        becomes A - C_E D_EE^-1 B_E (a stiffness on those pairs: normal
        for an open row, across the slip direction for a slipping node in
        3D) and the u residual loses C_E D_EE^-1 r_E.  The load that a
        slipping node's tau takes from its glued lam (C_E D_EE^-1 D_EG,
        friction following the normal traction) is left out of the glued
        solve; the outer Krylov method corrects it."""
        m = self.maps
        self.B, self.C, self.D = m.contact_blocks(K)
        self.e_inv = block_inverse(self.D, m.glued.getArray(readonly=True) == 0.0)
        Bs = self.e_inv.matMult(self.B)
        CB = self.C.matMult(Bs)
        A.axpy(-1.0, CB, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        for obj in (Bs, CB):
            obj.destroy()

    def _contact_products(self, A):
        """A P^T and P A, with P (``maps.pt``) the contact rows' normals: the
        two products of the glue's apply with the elasticity touch only the
        fracture's unknowns (P^T s lives on them; P reads only their rows), so
        they are formed once here instead of two products with all of A per
        application."""
        pt = self.maps.pt
        ptT = pt.transpose(PETSc.Mat())           # (transpose() alone would turn pt in place)
        self.A_pt = A.matMult(ptT)
        self.pt_A = pt.matMult(A)
        ptT.destroy()

    def _set_inner(self, pc, AZ, context, u_full, Z=None):
        """The solve of the (glued) elasticity AZ on the u unknowns
        ``u_full``: its near-nullspace is the rigid-body modes (Z^T r: they
        are glued displacements); P2 u gets the two-level p-multigrid of
        ``pmg`` unless ``-contact_pmg 0``, else one GAMG V-cycle."""
        comm = AZ.getComm()
        modes = mode_vectors(context, u_full)
        fine = []
        for r in modes:
            v = AZ.createVecRight()
            Z.multTranspose(r, v) if Z is not None else r.copy(v)
            fine.append(v)
        AZ.setNearNullSpace(orthonormal_nullspace(fine, comm))
        if self.ksp is not None:
            self.ksp.destroy()
        prefix = (pc.getOptionsPrefix() or "") + "contact_"
        # three smoothing steps per level unless the user says otherwise (Scene 2's
        # layered mesh, 58 k unknowns: 37 -> 30 Krylov per Newton at the same cost)
        context.proposals.propose({prefix + "mg_levels_ksp_max_it": str(SMOOTHING_STEPS)})
        self.ksp = PETSc.KSP().create(comm=comm)
        self.ksp.setOptionsPrefix(prefix)
        self.ksp.setOperators(AZ)
        self.ksp.setType("preonly")
        interp = context.p1_interpolation()
        if interp is not None and PETSc.Options(prefix).getBool("pmg", True):
            P, coarse = pmg.glued_interpolation(interp, u_full, Z, comm)
            self._coarse = pmg.set_two_level(self.ksp, AZ, P, [coarse(r) for r in modes])
            P.destroy()
        else:
            self.ksp.getPC().setType("gamg")
        for r in modes:
            r.destroy()
        self.ksp.setFromOptions()
        refuse_vector_interpolation(prefix, AZ)
        self.ksp.setUp()

    def apply(self, pc, x, y):
        if self.maps is None:
            self.ksp.solve(x, y)
            return
        m, w = self.maps, self._work
        xu, x_con = x.getSubVector(m.iu), x.getSubVector(m.ilam)
        xl = w["xl"]
        m.rot.mult(x_con, xl)                                    # the contact rows, rotated
        g = m.glued.getArray(readonly=True)
        self.e_inv.mult(xl, w["s"])
        self.C.mult(w["s"], w["ru"])
        w["ru"].aypx(-1.0, xu)                                   # r_u - C_E D_EE^-1 r_E
        w["s"].getArray()[:] = g * xl.getArray(readonly=True) / _safe(m.b.getArray(readonly=True))
        m.pt.multTranspose(w["s"], w["up"])                      # 1. u_p = P (r_lam / b)
        self.A_pt.mult(w["s"], w["t"])                           #    (A u_p = (A P^T) s)
        w["t"].aypx(-1.0, w["ru"])                               # 2. r_u - A u_p
        self.Z.multTranspose(w["t"], w["zr"])
        self.ksp.solve(w["zr"], w["v"])
        self.Z.mult(w["v"], w["u"])
        w["u"].axpy(1.0, w["up"])                                #    u = Z v + u_p
        m.pt.mult(w["ru"], w["lam"])                             # 3. the force the glue carries,
        self.pt_A.mult(w["u"], w["s"])                           #    P (r_u - A u)
        w["lam"].axpy(-1.0, w["s"])
        w["lam"].getArray()[:] *= g / _safe(m.c.getArray(readonly=True))
        self.B.mult(w["u"], w["s"])                              #    and the eliminated rows:
        self.D.multAdd(w["lam"], w["s"], w["s"])                 #    D_EE^-1 (r_E - B_E u - D_EG x_G)
        w["s"].aypx(-1.0, xl)
        self.e_inv.multAdd(w["s"], w["lam"], w["lam"])
        m.rot.multTranspose(w["lam"], w["s"])                    # back from the rotated rows
        w["s"].copy(w["lam"])
        x.restoreSubVector(m.iu, xu)
        x.restoreSubVector(m.ilam, x_con)
        for iset, v in ((m.iu, w["u"]), (m.ilam, w["lam"])):
            sub = y.getSubVector(iset)
            v.copy(sub)
            y.restoreSubVector(iset, sub)

    def _release(self):
        for v in self._work.values():
            v.destroy()
        self._work = {}
        for obj in (self.Z, self._coarse, self.B, self.C, self.D, self.e_inv, self.A_pt, self.pt_A):
            if obj is not None:
                obj.destroy()
        self._coarse = self.B = self.C = self.D = self.e_inv = self.A_pt = self.pt_A = None
        if self.maps is not None and self._own_maps:
            self.maps.destroy()
        self.maps = self.Z = None

    def reset(self, pc):
        self._release()
        if self.ksp is not None:
            self.ksp.destroy()
            self.ksp = None


#: BoomerAMG's vector (nodal) interpolation, which needs an operator of nodal blocks
VEC_INTERP = "pc_hypre_boomeramg_vec_interp_variant"


def refuse_vector_interpolation(prefix: str, A: PETSc.Mat) -> None:
    """A one-line error, not hypre's segmentation fault, for BoomerAMG's
    vector interpolation on the glued elasticity: its basis mixes a node's
    components (block size 1), and hypre 2.26 crashes on it (Scene 2, and
    partial_opening with ``-vi_fieldsplit_mech_contact_pc_type hypre
    -vi_fieldsplit_mech_contact_pmg false ..._vec_interp_variant 3``)."""
    if A.getBlockSize() != 1:
        return
    bad = sorted(k for k in PETSc.Options().getAll() if k.startswith(prefix) and k.endswith(VEC_INTERP))
    if bad:
        raise InputError(f"option -{bad[0]}: BoomerAMG's vector interpolation needs nodal blocks, and the "
                         "glued elasticity of the contact preconditioner has none (block size 1); "
                         "leave the option out")


def _safe(a: np.ndarray) -> np.ndarray:
    """A divisor with its zeros replaced by ones."""
    return np.where(a != 0.0, a, 1.0)
