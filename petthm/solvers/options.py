"""The solver options of a run (manual: solver guide, "Order of
precedence"): petthm proposes options, the user's options always win.

The options database is filled in this order, lowest precedence first:

1. PETSc's own defaults;
2. ``SOLVER_DEFAULTS`` (backward Euler, Newton, GMRES + GAMG, tolerances);
3. the scene's proposals (``Scene.solver_defaults``: a direct solve, a VI
   Newton method for contact), then ``-thm_dt_control error``'s TS
   adaptivity, then PETSc's own LU for serial 2D runs without bounds
   (``serial_plane_direct``);
4. above ``-thm_direct_max_unknowns`` unknowns with displacement, the block
   preconditioner (``recipes.BLOCK_RECIPE`` with the scene's changes,
   ``Scene.block_recipe``);
5. the user's options files and command line: a proposal is inserted only
   where the database has no value for its key.

``proposed_options`` computes 2-4 in one place; a run's ``Proposals``
inserts them and remembers which keys are petthm's, so that a misspelt
option of the user's is an error (``check_unused``) and proposals no solver
read are dropped before PETSc reports unused options (``drop_unused``)."""
from __future__ import annotations

from petsc4py import PETSc

from petthm import compat
from petthm.errors import InputError
from petthm.solvers.recipes import solver_defaults_by_size
from petthm.solvers.stepcontrol import error_control_defaults

SOLVER_DEFAULTS = {
    "ts_type": "beuler",
    "ts_adapt_type": "none",
    "snes_type": "newtonls",
    "snes_linesearch_type": "basic",
    "snes_rtol": "1e-10",
    "snes_atol": "1e-10",
    "snes_stol": "1e-14",
    "snes_max_it": "25",
    "ksp_type": "gmres",
    "ksp_rtol": "1e-10",
    "ksp_atol": "1e-14",
    "ksp_gmres_restart": "200",
    "ksp_max_it": "2000",
    "pc_type": "gamg",
}


def direct_solver_defaults(comm) -> dict[str, str]:
    """A sparse direct solve: MUMPS, else SuperLU_dist, else PETSc's LU
    (serial) or, in parallel, PETSc's LU on a redundant copy of the matrix."""
    out = {"ksp_type": "gmres", "ksp_max_it": "50"}
    for package in ("mumps", "superlu_dist"):
        if PETSc.Sys.hasExternalPackage(package):
            return dict(out, pc_type="lu", pc_factor_mat_solver_type=package)
    # PETSc's own LU does not pivot: a zero pivot (the rows of the contact
    # multipliers) is shifted and GMRES corrects the inexact LU.  The row swap
    # of -pc_factor_nonzeros_along_diagonal crashes
    # (PETSc 3.26.1, segmentation fault: contact_patch 3D) or stalls
    # (partial_opening, vinewtonssls) on the nodal contact rows of the dual
    # pairing; with the shift alone every contact and friction case converges
    lu = {"pc_factor_shift_type": "nonzero"}
    if comm.size == 1:
        return dict(out, pc_type="lu", **lu)
    # on the gathered copy, PETSc 3.26.1's inode LU stopped with "Node size not
    # yet supported" (error 56: Scene 2 with lumped heat terms on 2 ranks), so
    # the copy is factored without inodes
    redundant = {"redundant_" + k: v for k, v in lu.items()}
    return dict(out, pc_type="redundant", redundant_pc_type="lu", mat_no_inode="", **redundant)


def serial_plane_direct(defaults: dict[str, str], dim: int, ranks: int, bounded: bool) -> dict[str, str]:
    """The direct solve of a serial 2D run without bounded unknowns: PETSc's
    own LU in place of MUMPS or SuperLU_dist.  Measured (manual, performance):
    on 2D meshes PETSc's triangular solves are 4-5x faster than MUMPS's
    (P2 lauwerier, 3.7 k to 84 k unknowns) and its factorisation costs at most
    2x MUMPS's, so a run that reuses its factorisation (-thm_pc_reuse) is
    1.4-1.5x faster.  In 3D MUMPS factors ~4x faster (Scene 2, 13 k unknowns)
    and stays; so does every contact run (the VI rows: PETSc's LU does not
    pivot) and every parallel one."""
    direct = defaults.get("pc_type") == "lu" and defaults.get("pc_factor_mat_solver_type") in ("mumps",
                                                                                              "superlu_dist")
    if not direct or dim != 2 or ranks != 1 or bounded:
        return defaults
    out = {k: v for k, v in defaults.items() if k != "pc_factor_mat_solver_type"}
    return dict(out, pc_factor_mat_solver_type="petsc", pc_factor_shift_type="nonzero")


#: options PETSc reads only at finalize or start-up; never "unused"
_LATE_OPTIONS = ("log_view", "options_left", "options_file", "help", "malloc", "info",
                 "memory_view", "log_", "on_error", "no_signal_handler", "fp_trap",
                 "check_pointer_intensity", "viewer_binary", "history", "options_monitor", "mpi_")


#: a solver recipe may set the split of a field the scene does not have
_RECIPE_SPLITS = tuple(f"{pre}fieldsplit_{f}_" for f in ("u", "pm", "pf", "Tm", "Tf", "lam",
                                                         "rest") for pre in ("", "vi_"))


def proposed_options(scene, has_displacement: bool, bounded: bool, dim: int, ranks: int, unknowns: int,
                     control, comm) -> dict[str, str]:
    """Layers 2-4 of the module docstring for a run of ``scene`` (its run
    options: ``-thm_dt_control``, ``-thm_direct_max_unknowns``), merged: a
    later layer's value wins over an earlier one's."""
    run = scene.run
    options = dict(SOLVER_DEFAULTS, **scene.solver_defaults(comm),
                   **(error_control_defaults(control) if run.dt_control == "error" else {}))
    options = serial_plane_direct(options, dim, ranks, bounded)
    snes_type = PETSc.Options().getString("snes_type", options["snes_type"])
    return solver_defaults_by_size(options, has_displacement, unknowns, run.direct_max_unknowns,
                                   scene.block_recipe(snes_type))


class Proposals:
    """The options petthm inserted into the options database of a run (see
    the module docstring): never the user's, whose values always win."""

    def __init__(self):
        self.names: set[str] = set()

    def propose(self, options: dict[str, str]) -> None:
        """Insert the options the user has not set."""
        opts = PETSc.Options()
        for k, v in options.items():
            if not opts.hasName(k):
                opts.setValue(k, v)
                self.names.add(k)

    def users_options(self) -> dict[str, str]:
        """The options the user gave: the database less petthm's proposals."""
        return {k: v for k, v in PETSc.Options().getAll().items() if k not in self.names}

    def check_unused(self) -> None:
        """An ``InputError`` naming the first option of the user's that nothing
        has read (a misspelling, or an option not valid for this scene)."""
        left = [o for o in compat.unused_options()
                if not o.startswith(_LATE_OPTIONS + _RECIPE_SPLITS) and o not in self.names]
        if left:
            raise InputError(f"option -{left[0]} was not used by any solver or petthm component "
                             "(misspelt, or not valid for this scene)")

    def drop_unused(self) -> None:
        """Remove the proposals no solver read (e.g. the direct-solver defaults
        when a recipe picks another preconditioner), so that PETSc's report of
        unused options at exit names only the user's."""
        opts = PETSc.Options()
        for o in compat.unused_options():
            if o in self.names:
                opts.delValue(o)


__all__ = ["SOLVER_DEFAULTS", "Proposals", "direct_solver_defaults", "proposed_options",
           "serial_plane_direct"]
