"""The rock's wall conduction in the fracture heat's SUPG residual (theory
manual, "Equations: fracture heat").

With the equilibrium exchange (the wall nodes of Tm tied to Tf,
manual, verification: fracture flow and heat) the fracture heat equation in strong form is

    C dTf/dt + b . grad Tf - div(a lambda_f grad Tf) - q_w = 0,
    q_w = sum_s d_s . Lambda_m grad Tm_s,

with d_s the unit normal from the fracture into the rock on side s (- n on
the - side, + n on the + side) and Tm_s the rock temperature in the cell
next to the face on that side: the heat the rock conducts into the water.
The Galerkin equations carry q_w without writing it (the tie sums the
fracture rows and the rock's wall rows), but the SUPG residual R must
carry it to be consistent: without it R = q_w != 0 at the exact solution,
an O(tau) error that, in Lauwerier's problem (where q_w is what cools the
rock), held P2 to P1's accuracy (manual, verification: Lauwerier study).

``grad Tm_s`` is that of the rock cell (an ``Adjacent`` field, assembled
from the rock cell's dofs at the fracture's quadrature points), so the
Jacobian gains the blocks d(Tf rows)/d(Tm of the two rock cells).  The
finite exchange (``nusselt``, a given hw) keeps its exchange out of R
(manual, verification: fracture flow and heat explains why) and gets no wall term.  The term is an
option (``-thm_fracture_supg_wall_conduction``, ``ModelBuilder.build``):
where the wall layers are thin against the fracture's cells the consistent
SUPG over- or undershoots by 1-6 % (measured; manual, verification: fracture flow and heat).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.discretisation.model import Adjacent, Side

SIDES = (Side.MINUS, Side.PLUS)


@dataclass(frozen=True)
class WallConduction:
    """The rock field (``field``, Tm) and its conductivity Lambda_m (a number
    or a (d, d) tensor) whose wall flux enters the fracture's SUPG residual."""
    field: str
    conductivity: object

    def direction(self, side: Side, ctx) -> np.ndarray:
        """Lambda_m d_s (nc, 1, d): the wall flux is its dot product with grad Tm_s."""
        d = side.sign * ctx.normals
        L = self.conductivity
        return L * d if np.isscalar(L) else np.einsum("ab,cqb->cqa", np.asarray(L), d)


def wall_flux(wall: WallConduction, ctx) -> np.ndarray:
    """q_w = sum_s d_s . Lambda_m grad Tm_s at the fracture's points (nc, nq), W/m2."""
    return sum((ctx.grad(Adjacent(wall.field, s))[:, :, 0, :] * wall.direction(s, ctx)).sum(axis=2)
               for s in SIDES)


def supg_g3(wall: WallConduction, side: Side, tau: np.ndarray, b: np.ndarray, ctx) -> np.ndarray:
    """d(tau R b)/d(grad Tm_s) = -tau b (Lambda_m d_s)^T: (nc, nq, 1, d, 1, d)."""
    m = wall.direction(side, ctx)
    return -(tau[..., None, None] * b[..., :, None] * m[:, :, None, :])[:, :, None, :, None, :]
