"""The wall heat exchange between a fracture's water and the rock on its
faces (theory manual, "Equations: fracture heat"): a finite coefficient hw,
a number or hw = Nu lambda_f / (2 a) at the local aperture of a deformable
fracture.  The equilibrium exchange ties the rock's wall nodes to Tf instead
(``builders.ModelBuilder.fracture_heat``)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from petthm.discretisation.model import CellJacobian, CellResidual, Domain, Region
from petthm.physics.kernels.flow import g0_block
from petthm.physics.kernels.regional import at


@dataclass(frozen=True)
class ApertureExchange:
    """Wall heat-transfer coefficient hw = K / a of a deformable fracture
    (theory manual, "Equations: fracture heat": K = Nu lambda_f / 2)."""
    K: float
    aperture: object

    def value(self, ctx):
        return self.K / self.aperture.state(ctx).a

    def derivative(self, ctx):
        """d hw / d a."""
        return -self.K / self.aperture.state(ctx).a ** 2


def _hw(hw, ctx):
    """A wall coefficient: a number (one per fracture: a ``Regional``), or
    per point (``ApertureExchange``)."""
    hw = at(hw, ctx)
    return hw.value(ctx) if isinstance(hw, ApertureExchange) else hw


# -- wall heat exchange (fracture region) ----------------------------------------------
def exchange_terms(Tf: str, walls: tuple, hw, lumped: bool = False) -> tuple[list, list]:
    """q_h = hw (Tf - Tm_s) on each face s (theory manual, "Equations: fracture heat"): a sink in the
    fracture heat equation and the equal source in the matrix heat equation
    (test functions of the ``walls``: the ``Trace`` of Tm on each face).
    ``hw``: a number, or an ``ApertureExchange`` (hw = K/a with the local
    aperture; then the blocks with respect to lam and u+- through a as
    well).  ``lumped``: integrated with the vertex rule (row-sum lumping, P1
    fields)."""
    region = Region(Domain.FRACTURE, lumped=lumped)

    def coefficient(ctx):
        v = _hw(hw, ctx)
        return v[..., None] if np.ndim(v) else v

    def f0_f(ctx):
        return coefficient(ctx) * sum(ctx.value(Tf) - ctx.value(s) for s in walls)

    def f0_m(s, ctx):
        return coefficient(ctx) * (ctx.value(s) - ctx.value(Tf))

    def coef(v, ctx):
        return g0_block(v * _hw(hw, ctx))
    res = [CellResidual(Tf, f0_f, None, region=region)]
    res += [CellResidual(s, partial(f0_m, s), None, region=region) for s in walls]
    jac = [CellJacobian(Tf, Tf, g0=partial(coef, float(len(walls))), region=region)]
    for s in walls:
        jac += [CellJacobian(Tf, s, g0=partial(coef, -1.0), region=region),
                CellJacobian(s, Tf, g0=partial(coef, -1.0), region=region),
                CellJacobian(s, s, g0=partial(coef, 1.0), region=region)]
    if isinstance(hw, ApertureExchange):
        def s0_f(ctx):
            return hw.derivative(ctx) * sum(ctx.value(Tf)[..., 0] - ctx.value(s)[..., 0] for s in walls)

        def s0_m(s, ctx):
            return hw.derivative(ctx) * (ctx.value(s)[..., 0] - ctx.value(Tf)[..., 0])
        jac += hw.aperture.jacobians(Tf, s0_f, None, region)
        for s in walls:
            jac += hw.aperture.jacobians(s, partial(s0_m, s), None, region)
    return res, jac
