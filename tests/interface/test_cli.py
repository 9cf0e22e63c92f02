"""Command line: help, and one-line errors that name the problem."""
import subprocess
import sys

import numpy as np
import pytest
from petsc4py import PETSc

from conftest import ROOT, run_petthm


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "petthm", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)


def test_help_lists_scenes():
    p = _cli("-help")
    assert p.returncode == 0
    for name in ("heat_mms", "heat_erfc", "heat_advection", "lauwerier", "rigid_fracture", "leakoff_heat"):
        assert name in p.stdout


def test_scene_help_lists_parameters_with_units_and_defaults():
    p = _cli("heat_erfc", "-help")
    assert p.returncode == 0
    line = next(l for l in p.stdout.splitlines() if "-thm_rock_conductivity" in l)
    assert "2.9" in line and "W/(m K)" in line


def _one_line_error(proc):
    err = [l for l in proc.stderr.strip().splitlines() if l.strip()]
    assert proc.returncode == 2, proc.stderr + proc.stdout
    assert len(err) == 1, proc.stderr
    return err[0]


def test_misspelt_thm_option_is_an_error(tmp_path):
    proc, _ = run_petthm("heat_mms", tmp_path, "-thm_rock_conductivty", "2", check=False)
    msg = _one_line_error(proc)
    assert "unknown option -thm_rock_conductivty" in msg and "-thm_rock_conductivity" in msg


def test_misspelt_petsc_option_is_an_error(tmp_path):
    proc, _ = run_petthm("heat_mms", tmp_path, "-ksp_tpye", "cg", check=False)
    assert "option -ksp_tpye was not used" in _one_line_error(proc)


def test_missing_mesh_file_is_an_error(tmp_path):
    proc, _ = run_petthm("heat_mms", tmp_path, "-thm_mesh_file", tmp_path / "nope.msh", check=False)
    msg = _one_line_error(proc)
    assert "nope.msh" in msg and "does not exist" in msg and "-thm_mesh_file" in msg


@pytest.mark.parametrize("value", ["-1", "inf", "nan"])
def test_out_of_range_or_non_finite_conductivity_is_an_error(tmp_path, value):
    proc, _ = run_petthm("heat_erfc", tmp_path, "-thm_rock_conductivity", value, check=False)
    msg = _one_line_error(proc)
    assert f"-thm_rock_conductivity = {float(value)}" in msg and "(0, inf)" in msg


def test_missing_options_file_is_an_error(tmp_path):
    proc, _ = run_petthm("heat_mms", tmp_path, "-options_file", tmp_path / "x.opts", check=False)
    assert "x.opts" in _one_line_error(proc)


def test_unknown_scene_is_an_error(tmp_path):
    proc, _ = run_petthm("heat_nope", tmp_path, check=False)
    assert "unknown scene 'heat_nope'" in _one_line_error(proc)


@pytest.mark.parametrize("opts,words", [
    (("-thm_fluid_viscosity", "foo"), ("-thm_fluid_viscosity", "water")),
    (("-thm_fracture_heat_exchange", "-3"), ("-thm_fracture_heat_exchange", "nusselt")),
    (("-thm_fracture_heat_exchange", "nusselt"), ("-thm_fracture_heat_exchange", "permeable")),
    (("-thm_rock_permeability", "1,2,3,4"), ("-thm_rock_permeability", "1, 2 or 3 values")),
    (("-thm_rock_permeability", "1,2,3"), ("-thm_rock_permeability", "not positive semi-definite")),
    (("-thm_rock_permeability", "-1e-14"), ("-thm_rock_permeability", "not positive semi-definite")),
])
def test_bad_fracture_input_is_a_one_line_error(tmp_path, opts, words):
    proc, _ = run_petthm("rigid_fracture", tmp_path, *opts, "-thm_mesh_size", 60,
                         "-thm_scene1_fracture_size", 10, check=False)
    msg = _one_line_error(proc)
    assert all(w in msg for w in words), msg


@pytest.mark.parametrize("opts,words", [
    (("-pc_type", "foo"), ("PETSc refused the solver options", "PC type foo")),
    (("-ksp_type", "gmress"), ("PETSc refused the solver options", "KSP type gmress")),
    (("-dm_refine", "-1"), ("PETSc refused the mesh options", "-1")),
    (("-ts_max_time", "-5"), ("-ts_max_time = -5", "> 0")),
    (("-ts_max_time", "0"), ("-ts_max_time = 0", "> 0")),
])
def test_bad_petsc_option_values_are_one_line_errors(tmp_path, opts, words):
    """Issue 15: PETSc's refusal of an option value is a one-line error with
    PETSc's own message, not its error stack and a traceback; a TS end time
    <= 0 is refused (it used to 'complete' after 0 steps)."""
    proc, _ = run_petthm("heat_erfc", tmp_path, *opts, check=False)
    msg = _one_line_error(proc)
    assert all(w in msg for w in words), msg


@pytest.mark.parametrize("ranks", [1, 2])
def test_a_misspelt_option_with_the_block_recipe_is_a_one_line_error(tmp_path, ranks):
    """Issue 15: a misspelt option is found after the first step; with the
    block recipe's Python preconditioners the run then crashed at exit
    (segmentation fault, exit 139: the error's traceback kept the TS alive
    into PETSc's finalisation) and on 2 ranks aborted with a traceback on
    every rank; now exit 2 and one line."""
    proc, _ = run_petthm("contact_patch", tmp_path, "-options_file", f"{ROOT}/options/solvers/block.opts",
                         "-ksp_foo", 1, ranks=ranks, check=False)
    mine = [line for line in proc.stderr.splitlines() if line.startswith("petthm")]
    assert proc.returncode == 2 and len(mine) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert "-ksp_foo" in mine[0]


def test_a_rock_too_narrow_for_the_end_time_is_refused(tmp_path):
    """Issue 16: lauwerier's rock must be wider than 4 sqrt(kappa t_final)
    (the 60 m default was too narrow past ~2e8 s); 0, the default, takes a
    width that fits."""
    proc, _ = run_petthm("lauwerier", tmp_path, "-thm_lauwerier_width", 60, "-thm_final_time", 1e9,
                         check=False)
    msg = _one_line_error(proc)
    assert "-thm_lauwerier_width = 60" in msg and "118 m" in msg, msg


def test_a_bad_option_of_the_block_recipe_is_a_one_line_error(tmp_path):
    """Issue 15: an option value the block recipe's inner solvers refuse
    surfaces at the first preconditioner set-up; it used to end in a
    traceback and a segmentation fault, now a one-line error (exit 2)."""
    proc, _ = run_petthm("contact_patch", tmp_path, "-options_file", f"{ROOT}/options/solvers/block.opts",
                         "-vi_fieldsplit_mech_pc_type", "foo", check=False)
    msg = _one_line_error(proc)
    assert "the block recipe (-vi_*)" in msg and "PC type foo" in msg, msg


@pytest.mark.parametrize("scene,opts", [
    ("lauwerier", ()),
    ("penny_impermeable", ("-options_file", f"{ROOT}/options/scenes/penny_impermeable.opts",
                           "-thm_scene2_fracture_size", 40, "-thm_scene2_well_size", 20,
                           "-thm_scene2_layer", 0)),
])
def test_a_failed_first_step_fails_cleanly(tmp_path, scene, opts):
    """Issue 15: a fracture scene whose first step cannot be solved
    (-snes_max_it 1) retries it smaller, then stops with exit code 1,
    status failed and a message naming the TS and SNES reasons (it used to
    end in a ZeroDivisionError in the balance monitor, with no summary)."""
    proc, s = run_petthm(scene, tmp_path, *opts, "-snes_max_it", 1, check=False)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert s["status"] == "failed" and s["steps"] == 0 and s["rejected_steps"] > 0
    assert "DIVERGED_STEP_REJECTED" in s["message"] and "SNES DIVERGED_MAX_IT" in s["message"]
    assert "the run stopped" in proc.stdout


def test_progress_estimate_counts_the_geometric_steps():
    """Issue 15: the steps left after step 1 of a geometric schedule (Scene
    2: 1e3 s, x1.2, at most 2e7 s, to 1e9 s) are counted, not taken from
    the simulated-time fraction (which overestimated the wall time 1e4x)."""
    from petthm.solvers.timestepper import StepControl
    c = StepControl(final_time=1e9, dt_initial=1e3, growth=1.2, dt_max=2e7)
    t, dt, n = 1e3, 1e3, 0
    while t < c.final_time * (1 - 1e-12):
        dt = min(dt * c.growth, c.dt_max, c.final_time - t)
        t += dt
        n += 1
    assert c.steps_left(1e3, 1e3) == n
    assert StepControl(final_time=10.0, dt_initial=1.0).steps_left(3.0, 1.0) == 7
    assert c.steps_left(c.final_time, 2e7) == 0


def test_a_collapsed_time_step_is_a_failure():
    """Issue 15: a run whose step was cut by rejections to below 1e-10 of
    the end time (and 1e-6 of the first step) is stopped as failed instead
    of going on for ever on such steps (seen: friction_patch, steps of
    1e-11 s in a 1 s run); the last step, clipped to the end time, may be
    short."""
    from petthm.solvers.timestepper import StepControl
    c = StepControl(final_time=1.0, dt_initial=0.2)
    assert c.dt_floor() == pytest.approx(1e-10)
    assert c.collapsed(1e-11, 0.5) and not c.collapsed(1e-9, 0.5)
    assert not c.collapsed(1e-11, 1.0)                   # landing on the end time
    long_run = StepControl(final_time=1e9, dt_initial=1e-3)
    assert not long_run.collapsed(1e-3, 1e-3)             # a small first step is not a collapse


class _ScheduleTS:
    """The part of a TS that TimeStepper._post_step uses: steps of the
    proposed size, except the tries ``cuts`` names (step number -> how
    many tries were rejected, each cutting the step by 4 as TS does)."""

    def __init__(self, dt, cuts):
        from petsc4py import PETSc
        self.comm, self.t, self.dt, self.n, self.rejections, self.cuts = PETSc.COMM_SELF, 0.0, dt, 0, 0, cuts

    def advance(self):
        for _ in range(self.cuts.get(self.n + 1, 0)):
            self.dt, self.rejections = self.dt / 4, self.rejections + 1
        self.t, self.n = self.t + self.dt, self.n + 1

    def getTime(self):
        return self.t

    def getTimeStep(self):
        return self.dt

    def setTimeStep(self, dt):
        self.dt = dt

    def getStepRejections(self):
        return self.rejections

    def getStepNumber(self):
        return self.n

    def getSolution(self):
        return None


def _steps(control, cuts, n, start=0.0, dt=None):
    """The steps of ``n`` accepted steps from ``start`` (a restart's time and
    step ``dt``; default: the run's start) under ``control``."""
    from petthm.solvers.timestepper import TimeStepper
    stepper = TimeStepper.__new__(TimeStepper)          # the schedule alone, without a problem
    stepper._start_schedule(control, control.dt_initial)
    stepper._user_monitor = None
    ts = stepper.ts = _ScheduleTS(dt or control.dt_initial, cuts)
    ts.t = start
    stepper._land_first_step()
    taken = []
    for _ in range(n):
        ts.advance()
        taken.append(ts.dt)
        stepper._post_step(ts)
    return np.array(taken)


@pytest.mark.parametrize("growth", [1.0, 1.1])
def test_a_step_cut_by_rejections_grows_back_to_the_schedule(growth):
    """Issue 15: a step cut by rejected tries grows back (x2 per accepted
    step) to where the schedule would be, in a constant schedule (it used
    to stay cut for the rest of the run) and a geometric one (it used to
    grow back at x1.1); without rejections the schedule is unchanged."""
    from petthm.solvers.timestepper import StepControl
    c = StepControl(final_time=1e9, dt_initial=1.0, growth=growth, dt_max=5.0)
    plain = _steps(c, {}, 30)
    assert np.allclose(plain, np.minimum(growth ** np.arange(30), 5.0))
    cut = _steps(c, {3: 2}, 30)                          # step 3 taken at 1/16 of its size
    assert cut[2] == pytest.approx(plain[2] / 16)
    assert np.allclose(cut[3:6] / cut[2:5], 2.0)         # x2 while it grows back
    assert np.allclose(cut[10:], plain[10:])             # back on the schedule


def test_a_hit_time_is_reached_without_a_sliver_step():
    """A hit time (an output time) closer than two steps is reached in two
    equal steps, and the steps after it are the schedule's again, also when
    a landing step was rejected.  Seen on Scene 3: 0.2-year steps left 6 500 s
    to 20 years, that sliver's first try failed (a preconditioner kept from
    the long steps), and the growth restarted from the sliver at x1.1 (68
    steps back to 0.2 years); in a constant schedule the step stayed cut for
    the rest of the run."""
    from petthm.solvers.timestepper import StepControl
    c = StepControl(final_time=100.0, dt_initial=10.0, growth=1.0, dt_max=10.0, hit_times=(31.0,))
    plain = _steps(c, {}, 11)
    print("steps", plain)
    # the code before took 10, 10, 10, 1, 10, ... (a 1-s sliver), and the final time the same way
    assert plain == pytest.approx([10, 10, 5.5, 5.5, 10, 10, 10, 10, 10, 9.5, 9.5])
    cut = _steps(c, {4: 1}, 13)                          # the step landing on 31 cut by a rejected try
    print("with a rejected landing step", cut)
    assert 31.0 in np.round(np.cumsum(cut), 12)
    # back on the schedule (the code before stayed at 1 s for the rest of the run)
    assert cut[8:] == pytest.approx([10.0] * 5)
    # a restart 10.3 s before a new final time, its checkpoint's step 10 s: two equal steps (the code
    # before took 10 s and a 0.3-s sliver; seen restarting Scene 3 mid-run), and before the next hit
    # time from a restart the same
    assert _steps(c, {}, 2, start=89.7, dt=10.0) == pytest.approx([5.15, 5.15])
    assert _steps(c, {}, 4, start=15.0, dt=10.0) == pytest.approx([8.0, 8.0, 10.0, 10.0])


@pytest.mark.parametrize("size,ranks", [(1e-6, 1), (1e-9, 1), (1e-6, 2)])
def test_a_mesh_beyond_the_cell_limit_is_refused_before_meshing(tmp_path, size, ranks):
    """Issue 15: contact_patch -thm_mesh_size 1e-6 used to hang in gmsh and
    1e-9 to give a coarser mesh silently; now a one-line error names the
    size, the lower bound on the cells and -thm_max_cells (on every rank)."""
    proc, _ = run_petthm("contact_patch", tmp_path, "-thm_mesh_size", size, ranks=ranks, check=False)
    if ranks == 1:
        msg = _one_line_error(proc)
    else:                                    # mpiexec adds its own report of the exit code
        mine = [line for line in proc.stderr.splitlines() if line.startswith("petthm")]
        assert proc.returncode == 2 and len(mine) == 1 and "Traceback" not in proc.stderr, proc.stderr
        msg = mine[0]
    assert f"mesh size {size:g} m" in msg and "-thm_max_cells" in msg


@pytest.mark.parametrize("dim,size", [(2, 0.1), (2, 0.02), (3, 0.25), (3, 0.1)])
def test_fewest_cells_is_a_lower_bound(dim, size):
    """The bound the cell limit uses is below gmsh's count for a unit
    square or cube at that largest size (measured: 161 against 1140
    tetrahedra at 0.25)."""
    import gmsh

    from petthm.mesh.limits import fewest_cells
    gmsh.initialize(["gmsh"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        (gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1) if dim == 3 else gmsh.model.occ.addRectangle(0, 0, 0, 1, 1))
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.model.mesh.generate(dim)
        cells = len(gmsh.model.mesh.getElements(dim)[1][0])
    finally:
        gmsh.finalize()
    print(dim, size, "bound", fewest_cells(1.0, size, dim), "gmsh", cells)
    assert fewest_cells(1.0, size, dim) < cells


def test_a_garbage_options_file_is_a_one_line_error(tmp_path):
    """Issue 15: an options file with a line PETSc cannot parse used to end
    in PETSc's error banner and a traceback."""
    bad = tmp_path / "bad.opts"
    bad.write_text("-thm_final_time 10\ngarbage %%% ]]]\n")
    proc, _ = run_petthm("heat_erfc", tmp_path / "out", "-options_file", bad, check=False)
    msg = _one_line_error(proc)
    assert "bad.opts' line 2" in msg and "garbage" in msg


def test_a_corrupt_mesh_file_is_a_one_line_error(tmp_path):
    """Issue 15: a .msh file gmsh's reader refuses (it used to be a traceback)."""
    msh = tmp_path / "corrupt.msh"
    msh.write_text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\nxx\n")
    proc, _ = run_petthm("heat_erfc", tmp_path / "out", "-thm_mesh_file", msh, check=False)
    msg = _one_line_error(proc)                 # PETSc's own words differ between versions
    assert "PETSc refused the mesh file" in msg and "corrupt.msh" in msg


@pytest.mark.parametrize("ranks", [1, 2])
def test_an_output_folder_that_cannot_be_created_is_an_error(tmp_path, ranks):
    """Issue 15: -thm_output_dir under a file (it used to be a traceback;
    on 2 ranks every rank stops alike)."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    proc, _ = run_petthm("heat_erfc", blocker / "out", ranks=ranks, check=False)
    mine = [line for line in proc.stderr.splitlines() if line.startswith("petthm")]
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert len(mine) == 1 and "-thm_output_dir" in mine[0] and "cannot be created" in mine[0]


def test_a_mesh_that_does_not_fit_the_scene_is_a_one_line_error(tmp_path):
    """Issue 15: a fracture scene given a mesh without fractures, a scene
    without fracture physics given a split mesh, a mesh of another dimension
    (heat_erfc used to fail in its monitor with a broadcasting error), and a
    scene whose set-up fails on a user's mesh (an AttributeError traceback):
    one-line errors naming the mesh file."""
    run_petthm("heat_mms", tmp_path / "plain3d", "-thm_mms_dim", 3, "-thm_mesh_size", 0.5)
    run_petthm("heat_mms", tmp_path / "plain2d", "-thm_mesh_size", 0.5)
    run_petthm("contact_patch", tmp_path / "cracked", "-thm_contact_dim", 2, "-thm_final_time", 0.25)
    plain, cracked = tmp_path / "plain3d" / "mesh.msh", tmp_path / "cracked" / "mesh.msh"
    plain2d = tmp_path / "plain2d" / "mesh.msh"
    cases = [("contact_patch", plain, "has no fracture"), ("heat_mms", cracked, "has fractures"),
             ("heat_erfc", plain, "is 3D, but scene heat_erfc is 2D"),
             ("lauwerier", plain, "is 3D, but scene lauwerier is 2D (option -thm_lauwerier_dim = 2)"),
             ("lauwerier", plain2d, "does not fit scene lauwerier")]
    for scene, mesh, words in cases:
        proc, _ = run_petthm(scene, tmp_path / f"{scene}_out", "-thm_mesh_file", mesh, check=False)
        msg = _one_line_error(proc)
        assert words in msg and str(mesh) in msg, msg


def test_a_block_recipe_that_leaves_out_a_field_is_an_error(tmp_path):
    """-vi_groups must place every field of the scene in a split."""
    proc, _ = run_petthm("contact_patch", tmp_path, "-thm_contact_dim", 2, "-options_file",
                         f"{ROOT}/options/solvers/block.opts", "-vi_groups", "mech=u", check=False)
    msg = _one_line_error(proc)
    assert "-vi_groups = mech=u leaves out the field(s) lam" in msg


@pytest.mark.skipif(not PETSc.Sys.hasExternalPackage("hypre"), reason="PETSc without hypre")
def test_boomeramg_vector_interpolation_on_the_glued_elasticity_is_an_error(tmp_path):
    """hypre's vector interpolation on the contact preconditioner's glued
    elasticity (block size 1) crashed with a segmentation fault; now a
    one-line error naming the option.  Negative control: BoomerAMG without it runs."""
    opts = ("-thm_contact_dim", 2, "-options_file", f"{ROOT}/options/solvers/block.opts",
            "-vi_fieldsplit_mech_contact_pc_type", "hypre", "-vi_fieldsplit_mech_contact_pmg", "false")
    proc, _ = run_petthm("contact_patch", tmp_path / "vec", *opts,
                         "-vi_fieldsplit_mech_contact_pc_hypre_boomeramg_vec_interp_variant", 3, check=False)
    msg = _one_line_error(proc)
    assert "-vi_fieldsplit_mech_contact_pc_hypre_boomeramg_vec_interp_variant" in msg, msg
    assert "block size 1" in msg, msg
    _, summary = run_petthm("contact_patch", tmp_path / "plain", *opts)
    assert summary["status"] == "completed"


def test_a_singleton_run_isolates_open_mpi_and_a_launched_one_does_not():
    """Without mpiexec petthm asks Open MPI for an isolated singleton (no
    support daemon, no network probe); under a launcher, or with the user's own value, it
    leaves the environment alone."""
    from petthm.__main__ import isolate_singleton
    env = {}
    isolate_singleton(env)
    assert env == {"OMPI_MCA_ess_singleton_isolated": "1", "OMPI_MCA_pml": "ob1"}
    for launched in ({"OMPI_COMM_WORLD_SIZE": "2"}, {"PMIX_RANK": "0"}, {"PMI_RANK": "1"}):
        env = dict(launched)
        isolate_singleton(env)
        assert env == launched
    env = {"OMPI_MCA_ess_singleton_isolated": "0", "OMPI_MCA_pml": "ucx"}
    isolate_singleton(env)
    assert env == {"OMPI_MCA_ess_singleton_isolated": "0", "OMPI_MCA_pml": "ucx"}


def test_the_wall_term_on_thin_rock_layers_is_warned_about(tmp_path):
    """-thm_fracture_supg_wall_conduction on rock layers < 0.05 of the
    fracture's cells (0.05 m under 10 m here) prints one warning naming the
    option; the same mesh without the term, none."""
    mesh = ["-thm_scene1_layer", 0.05, "-thm_scene1_fracture_size", 10, "-thm_scene1_margin", 40,
            "-thm_mesh_size", 40, "-thm_final_time", 1e3]
    proc, _ = run_petthm("rigid_fracture", tmp_path / "on", *mesh,
                         "-thm_fracture_supg_wall_conduction", "true")
    warned = [ln for ln in proc.stdout.splitlines() if ln.startswith("petthm: warning:")]
    assert len(warned) == 1 and "-thm_fracture_supg_wall_conduction" in warned[0] and "0.00487" in warned[0]
    proc, _ = run_petthm("rigid_fracture", tmp_path / "off", *mesh)
    assert "petthm: warning:" not in proc.stdout
