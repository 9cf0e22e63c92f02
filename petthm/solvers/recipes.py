"""The block preconditioner's option sets (manual, solver guide): the recipe of
``options/solvers/block.opts`` (``BLOCK_RECIPE``), the scenes' changes to it
(their ``Scene.block_recipe``) and the size rule that proposes it in place
of a direct solve (``solver_defaults_by_size``).  Every set is a dict of
PETSc option names (no leading dash) and values; petthm inserts them only
where the user's options database has no value (``options.Proposals``)."""
from __future__ import annotations

from petsc4py import PETSc

from petthm import compat


def prefixed(prefix: str, options: dict[str, str]) -> dict[str, str]:
    """``options`` under the options prefix ``prefix`` (a split's or a solve's)."""
    return {prefix + k: v for k, v in options.items()}


#: a split's solve by one application of GAMG (the recipe's pm, pf, Tf and Tm)
GAMG_ONCE = {"ksp_type": "preonly", "pc_type": "gamg"}

#: the block preconditioner of options/solvers/block.opts (manual, solver guide), proposed by
#: ``solver_defaults_by_size`` for large problems with displacement; a test keeps the two equal
BLOCK_RECIPE = {
    "ksp_type": "fgmres",
    "ksp_rtol": "1e-6",
    "ksp_max_it": "500",
    "ksp_gmres_restart": "100",
    "ksp_gmres_cgs_refinement_type": "refine_ifneeded",   # the reported residual is the true one
    "pc_type": "python",
    "pc_python_type": "petthm.solvers.fieldsplit.VIFieldSplit",
    "vi_groups": "mech=u+lam+tau,pm=pm,pf=pf,Tf=Tf,Tm=Tm",
    "vi_pc_fieldsplit_type": "multiplicative",
    "vi_fieldsplit_mech_ksp_type": "preonly",
    "vi_fieldsplit_mech_pc_type": "python",
    "vi_fieldsplit_mech_pc_python_type": "petthm.solvers.contactpc.ContactNullspacePC",
    **prefixed("vi_fieldsplit_pm_", GAMG_ONCE),
    **prefixed("vi_fieldsplit_pf_", GAMG_ONCE),
    **prefixed("vi_fieldsplit_Tf_", GAMG_ONCE),
    **prefixed("vi_fieldsplit_Tm_", GAMG_ONCE),
}


#: BoomerAMG's settings for the glued elasticity of a layered mesh (manual, solver guide,
#: ): a strength threshold of 0.8 (GAMG's aggregation does not follow the
#: strong couplings across a layered mesh's thin cells), HMIS coarsening, extended+i
#: interpolation with at most 4 entries per row, aggressive coarsening on the first
#: level and a forward / backward Gauss-Seidel sweep (a symmetric cycle for CG at
#: half the smoothing cost): operator complexity 1.5 against 2.9, a third of the cost per cycle
BOOMERAMG = {"pc_type": "hypre", "pc_hypre_type": "boomeramg", "pc_hypre_boomeramg_strong_threshold": "0.8",
             "pc_hypre_boomeramg_coarsen_type": "HMIS", "pc_hypre_boomeramg_interp_type": "ext+i",
             "pc_hypre_boomeramg_P_max": "4", "pc_hypre_boomeramg_agg_nl": "1",
             "pc_hypre_boomeramg_relax_type_down": "SOR/Jacobi",
             "pc_hypre_boomeramg_relax_type_up": "backward-SOR/Jacobi"}

#: BoomerAMG's changes for a P2 glued elasticity on a layered mesh (``closed_fracture_recipe``):
#: no aggressive coarsening on the first level, and eight CG iterations on the cycle
P2_GLUED_AMG = {"pc_hypre_boomeramg_agg_nl": "0", "ksp_max_it": "8"}

#: the glued elasticity by four CG iterations on its multigrid cycle (a fixed
#: number: the outer FGMRES takes the changing preconditioner)
GLUED_CG = {"ksp_type": "cg", "ksp_max_it": "4", "ksp_norm_type": "none"}

#: the fracture's flow and heat with the rock's heat as one split, by GMRES to
#: 1e-3 on ILU(0) (block Jacobi in parallel) of its block with the glue's Schur term
FLOW_HEAT_SPLIT = {"ksp_type": "gmres", "ksp_rtol": "1e-3", "ksp_max_it": "200", "pc_type": "bjacobi",
                   "sub_pc_type": "ilu"}


#: the options prefix of the glued elasticity's solve in the block recipe's mechanics split
GLUED = "vi_fieldsplit_mech_contact_"


def glued(options: dict[str, str]) -> dict[str, str]:
    """``options`` for the glued elasticity's solve (prefixed ``GLUED``)."""
    return prefixed(GLUED, options)


#: the p-multigrid's P1 level (``pmg``, P2 u) by GAMG without aggressive coarsening (PETSc's
#: default: one level; the option's name is the PETSc version's, ``compat.GAMG_AGGRESSIVE_LEVELS``).
#: 3D Terzaghi, item 9's weak scaling on 1 / 2 / 4 / 8 ranks: 9.2 / 9.6 / 10.2 / 10.2 Krylov
#: iterations per Newton iteration (1.11x) against 11.2 / 13.0 / 14.3 / 15.8 (1.41x), 7 % more
#: wall time on one rank.  Not for Scene 3's default mesh: the same count there (335 / 338
#: against 334 / 334 in six 0.2-year steps) for 14 % more CPU time (manual, solver guide)
PMG_P1_NOT_AGGRESSIVE = {"mg_coarse_" + compat.GAMG_AGGRESSIVE_LEVELS: "0"}

#: the glued elasticity of a 2D crack under ``vinewtonssls``: GAMG's graph threshold 0.05
#: on the finest level only (coarser levels 0), so the aggregation follows the strong
#: couplings.  partial_opening, 1 022 to 124 164 unknowns: 6.2 / 7.4 / 7.8 Krylov per
#: Newton at levels 1 / 3 / 5 against 9.9 / 15.9 / 24.9; level 5 68 against 65 s wall.
#: Not for ``vinewtonrsls`` (16.1 -> 11.8 there, but 1.5x the wall time: the
#: hierarchy's set-up and cycle cost more) nor in 3D (the Galerkin products
#: filled; manual, solver guide)
SSLS_CRACK_GAMG = {"pc_gamg_threshold": "0.05", "pc_gamg_threshold_scale": "0"}


def flow_heat_recipe(groups: str, degree: int) -> dict:
    """The block path's changes for the splits ``groups`` (``-vi_groups``),
    of which ``flow_heat`` holds the flow and heat fields and ``mech`` the
    contact mechanics: ``flow_heat`` by GMRES to 1e-3 on ILU(0)
    (``FLOW_HEAT_SPLIT``), the glued elasticity by four CG iterations
    (``GLUED_CG``) on its multigrid cycle: with P1 u BoomerAMG where PETSc has
    hypre (``BOOMERAMG``), else the recipe's GAMG; with P2 u its p-multigrid.
    Block Gauss-Seidel between the flow and heat fields dropped the coupling
    that made the Krylov count, and one cycle's error in the elasticity
    multiplied it; each fix alone does little (manual, solver guide)."""
    out = {"vi_groups": groups,
           **glued(GLUED_CG),
           **prefixed("vi_fieldsplit_flow_heat_", FLOW_HEAT_SPLIT)}
    if degree == 1 and PETSc.Sys.hasExternalPackage("hypre"):
        out.update(glued(BOOMERAMG))
    return out


def closed_fracture_recipe(degree: int) -> dict:
    """The block path of a scene whose mechanics is loaded by a closed
    fracture's flow and by the rock's heat on a layered mesh (Scene 2): the
    mechanics, then {pf, Tf, Tm} as one split (``flow_heat_recipe``).
    Scene 2 default, five 1.3-1.8e7-s steps: 13.8 against 85.0 Krylov
    iterations per Newton iteration, KSPSolve 6.8 against 26.7 s (GAMG, no
    hypre: 20.7 against 176.6, 25.1 against 49.1 s).  P2 u, level 1 to
    1.7e7 s: 6.7 against 37.5 per Newton iteration.

    With P2 u and hypre, BoomerAMG's cycle on the P2 glued elasticity
    itself, in place of the p-multigrid: the layered mesh's thin cells
    defeat the P2 level's Chebyshev/Jacobi smoothing, as they defeat GAMG's
    aggregation with P1 u.  Scene 2 default with P2 u (241 080 unknowns),
    two 9.4e6-s steps, side by side: 24.8 against 32.2 Krylov iterations
    per Newton iteration, KSPSolve 110-112 against 182 s (manual, solver guide).

    On the P2 level BoomerAMG coarsens without aggressive coarsening and
    takes eight CG iterations (``P2_GLUED_AMG``), and the flow and heat
    split's block has no contact-Schur term (``-vi_contact_schur off``):
    both the cycle's error and that term's error grow with the mesh.
    Three 1-2e7-s steps at 2.1e8 s on levels 1 / 2 / 3 (32 013 / 98 844 /
    353 115 unknowns): 6.7 / 7.2 / 9.5 against 10.8 / 14.8 / 24.0 Krylov
    iterations per Newton iteration; on level 2, side by side, 16 % more
    CPU time (manual, solver guide)."""
    out = flow_heat_recipe("mech=u+lam+tau,pm=pm,flow_heat=pf+Tf+Tm", degree)
    if degree == 2 and PETSc.Sys.hasExternalPackage("hypre"):
        out.update(glued({"pmg": "0", **BOOMERAMG, **P2_GLUED_AMG}), vi_contact_schur="off")
    return out


def flow_heat_first_recipe(degree: int) -> dict:
    """The block path's changes for a scene with every field (u, lam, pm, pf,
    Tf, Tm): {pm, pf, Tf, Tm} as one split before the mechanics
    (``flow_heat_recipe``), the glued elasticity by six CG iterations with
    P1 u (four with P2 u) and one Chebyshev step on its p-multigrid's P2
    level.  The heat before the mechanics: the rock's thermal stress loads
    u, and the heat balances do not contain u.  Scene 3 (``InclinedPenny.block_recipe``
    has its measurements) and the coupled MMS (``CoupledMMS.block_recipe``)."""
    return {**flow_heat_recipe("flow_heat=pm+pf+Tf+Tm,mech=u+lam+tau", degree),
            **glued({"mg_levels_ksp_max_it": "1", **({"ksp_max_it": "6"} if degree == 1 else {})})}


def solver_defaults_by_size(scene_defaults: dict[str, str], has_displacement: bool, unknowns: int,
                            direct_max: int, block: dict[str, str] | None = None) -> dict[str, str]:
    """The scene's solver defaults, with the block preconditioner in place of
    its linear solver when the problem has displacement and more than
    ``direct_max`` unknowns (-thm_direct_max_unknowns): a direct solve's
    memory and time grow faster than the problem.  ``block``: the scene's
    changes to ``BLOCK_RECIPE`` (``Scene.block_recipe``)."""
    if not has_displacement or unknowns <= direct_max:
        return scene_defaults
    return {**scene_defaults, **BLOCK_RECIPE, **(block or {})}
