"""The block preconditioner of options/solvers/block.opts (issue 12): the
Schur-complement approximations it is built on, each against its negative
control, and parallel runs against serial ones."""

import pytest

from conftest import ROOT, read_csv, read_text, run_petthm

BLOCK = ("-options_file", f"{ROOT}/options/solvers/block.opts")
EXACT_SUBSOLVES = ("-vi_fieldsplit_mech_contact_pc_type", "lu", "-vi_fieldsplit_pm_pc_type", "lu",
                   "-vi_fieldsplit_pf_pc_type", "lu")


def krylov_per_newton(outdir) -> list[float]:
    """Krylov iterations per Newton iteration of every step."""
    rows = (read_csv(outdir / "history.csv"))[1:]
    return [int(r["ksp_its"]) / max(int(r["snes_its"]), 1) for r in rows]


def largest_krylov_per_newton(tmp_path, scene, common, variants) -> dict[str, float]:
    """Run ``scene`` with the options ``common`` and each variant's extra
    options (``{name: options}``); each must complete.  Returns the largest
    Krylov count per Newton iteration of any step, by variant."""
    its = {}
    for name, extra in variants.items():
        _, s = run_petthm(scene, tmp_path / name, *common, *extra)
        assert s["status"] == "completed"
        its[name] = max(krylov_per_newton(tmp_path / name))
    print("largest Krylov per Newton", its)
    return its


def test_fixed_stress_schur_approximation(tmp_path):
    """3D Terzaghi with incompressible fluid and grains (alpha = 1, c_f = 0:
    the pressure block has no storage, the Schur complement's storage is
    all fixed stress), sub-blocks solved exactly so that only the Schur
    approximation counts: with alpha^2/K_dr M/dt the Krylov count per
    Newton is about half of what the pressure block alone gives."""
    common = ("-options_file", f"{ROOT}/options/scenes/terzaghi.opts", *BLOCK, *EXACT_SUBSOLVES,
              "-thm_terzaghi_dim", 3, "-thm_mesh_size", 1, "-thm_final_time", 5,
              "-thm_fluid_compressibility", 0, "-thm_rock_biot_coefficient", 1)
    its = largest_krylov_per_newton(tmp_path, "terzaghi", common,
                                    {"fixed_stress": (), "control": ("-vi_fixed_stress", 0)})
    assert its["fixed_stress"] <= 13
    assert its["control"] >= 1.6 * its["fixed_stress"]


def test_contact_glue_gives_the_fracture_storage(tmp_path):
    """fracture_inflation with an incompressible fluid (P1 u): the storage
    of the closed fracture is the joint compliance, which the pf rows see
    only through lam.  With the glue's Schur term the run completes with
    few Krylov iterations per Newton, and the pf block is regular: an exact
    (LU) solve of it takes the first steps; without the term (the control)
    the pf block is singular: the same LU meets a zero pivot and the first
    step cannot be solved.  (With GAMG on the singular block the control
    failed too while FGMRES's Gram-Schmidt was not re-orthogonalised; with
    ``refine_ifneeded`` FGMRES gets past it: docs/solvers/index.md.)"""
    common = ("-options_file", f"{ROOT}/options/scenes/fracture_inflation.opts", *BLOCK,
              "-thm_fe_degree", 1)
    _, s = run_petthm("fracture_inflation", tmp_path / "glue", *common)
    its = krylov_per_newton(tmp_path / "glue")
    print("with the glue: steps", s["steps"], "Krylov per Newton max", max(its))
    assert s["status"] == "completed" and max(its) <= 25
    exact_pf = (*common, "-vi_fieldsplit_pf_pc_type", "lu", "-thm_final_time", 20)
    _, e = run_petthm("fracture_inflation", tmp_path / "exact", *exact_pf)
    _, c = run_petthm("fracture_inflation", tmp_path / "control", *exact_pf, "-vi_contact_schur", 0,
                      check=False)
    print("pf by LU, with the glue:", e["status"], e["steps"], "; control:", c["status"], c["steps"])
    assert e["status"] == "completed" and e["steps"] >= 1
    assert c["status"] == "failed" and c["steps"] == 0


def test_contact_schur_takes_the_face_loads_alone(tmp_path):
    """The coupled MMS, fracture closed (every field, the rock's pressure and
    temperature nodes on the walls tied into pf and Tf): the contact-Schur
    term built from the fracture terms of the u rows
    (``-vi_contact_schur faces``) completes in its 2 steps; built from every
    term of the u rows (``all``, the default, which Scene 2 needs: the Biot
    and thermal-strain body loads of the tied wall nodes, which the
    contact's recovery map takes for face loads: the control) the linear
    solves fail and steps are rejected (measured: 3 of 7, 500 Krylov
    iterations).  With the heat splits before the mechanics (Scene 3's
    order, ``Scene.block_recipe``) Tf keeps its own block, and ``all``
    completes as well.  The linear solves go to 1e-10, the recipe's
    tolerance when this was measured: at a recipe tolerance of 1e-6 the
    control rejects 1 step of 4 with PETSc 3.26 (2 682 Krylov against
    1 071 for ``faces``) and 3 of 7 with 3.18.  With a step control in
    which a rejected step near a hit time grows back to the step before
    it, the control's step collapses instead: 24 rejected, the run stops at
    t = 0.9 s (measured with 3.18).  With FGMRES re-orthogonalised
    the control's linear solves converge, its Newton iterates leave the
    fluid's range (mu(T) overflows) and, the Jacobian not being finite there,
    its steps are rejected: 70 rejected, the step collapses at t = 0.899 s
    (3.18); before the Jacobian's domain check the run crashed in GAMG's set-up.
    Newton starts each step from the last state (``-thm_predictor none``):
    on the line through the last two states the control rejected 1 step of
    4 with PETSc 3.26 (from the last state: 2 of 6), so the count would
    compare the start, not the Schur term."""
    common = ("-options_file", f"{ROOT}/options/scenes/coupled_mms.opts", "-thm_coupled_mms_state", "closed",
              *BLOCK, "-ksp_rtol", "1e-10", "-thm_predictor", "none")
    heat_first = ("-vi_groups", "Tf=Tf,Tm=Tm,mech=u+lam+tau,pm=pm,pf=pf", "-vi_contact_schur", "all")
    runs = {}
    for mode in ("faces", "all"):                    # the control may fail outright (check=False)
        _, runs[mode] = run_petthm("coupled_mms", tmp_path / mode, *common, "-vi_contact_schur", mode,
                                   check=(mode == "faces"))
    _, runs["heat_first"] = run_petthm("coupled_mms", tmp_path / "heat_first", *common, *heat_first)
    print({m: (s["steps"], s["rejected_steps"], s["ksp_iterations"]) for m, s in runs.items()})
    for ok in ("faces", "heat_first"):
        assert runs[ok]["status"] == "completed" and runs[ok]["rejected_steps"] == 0
        assert runs[ok]["ksp_iterations"] / runs[ok]["snes_iterations"] <= 110
    assert runs["all"]["rejected_steps"] >= 2


def test_contact_schur_option_is_checked(tmp_path):
    proc, _ = run_petthm("contact_patch", tmp_path, *BLOCK, "-vi_contact_schur", "some", check=False)
    assert proc.returncode == 2 and "-vi_contact_schur" in proc.stderr and "faces, all, off" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_p_multigrid_for_p2_displacement(tmp_path):
    """P2 u (3D Terzaghi, a 4 m wide column): the two-level p-multigrid of
    the elasticity needs clearly fewer Krylov iterations than GAMG on P2
    (measured: 8.7 against 14.0 per Newton here with the P1 level's GAMG
    without aggressive coarsening; 17 against 23 with it)."""
    common = ("-options_file", f"{ROOT}/options/scenes/terzaghi.opts", *BLOCK, "-thm_terzaghi_dim", 3,
              "-thm_terzaghi_width", 4, "-thm_mesh_size", 1, "-thm_final_time", 5)
    mean = {}
    for name, extra in (("pmg", ()), ("gamg", ("-vi_fieldsplit_mech_contact_pmg", 0))):
        _, s = run_petthm("terzaghi", tmp_path / name, *common, *extra)
        assert s["status"] == "completed"
        mean[name] = s["ksp_iterations"] / s["snes_iterations"]
    print("Krylov per Newton", mean)
    assert mean["pmg"] <= 0.8 * mean["gamg"]


def test_p_multigrid_coarse_level_without_aggressive_coarsening(tmp_path):
    """The p-multigrid's P1 level by GAMG without aggressive coarsening
    (Terzaghi's recipe, recipes.PMG_P1_NOT_AGGRESSIVE, under PETSc's name of
    the option, compat.GAMG_AGGRESSIVE_LEVELS): 3D Terzaghi, a 4 m wide column
    (13 712 unknowns) to 0.5 s.  Measured 134 against 158 Krylov
    iterations in 14 Newton iterations with PETSc's default of one
    aggressive level (the negative control), the same pressure; PETSc 3.26
    (MIS-2 aggressive coarsening, not graph squaring): 137 against 149."""
    from petthm.compat import GAMG_AGGRESSIVE_LEVELS
    common = ("-options_file", f"{ROOT}/options/scenes/terzaghi.opts", "-thm_terzaghi_dim", 3,
              "-thm_terzaghi_width", 4, "-thm_mesh_size", 0.7, "-thm_final_time", 0.5,
              "-thm_direct_max_unknowns", 0)
    _, s = run_petthm("terzaghi", tmp_path / "default", *common)
    _, c = run_petthm("terzaghi", tmp_path / "control", *common,
                      f"-vi_fieldsplit_mech_contact_mg_coarse_{GAMG_AGGRESSIVE_LEVELS}", 1)
    print("Krylov", s["ksp_iterations"], c["ksp_iterations"], "Newton", s["snes_iterations"])
    assert s["status"] == c["status"] == "completed"
    assert s["snes_iterations"] == c["snes_iterations"]
    assert s["ksp_iterations"] <= 0.95 * c["ksp_iterations"]
    assert abs(s["p_overshoot_max_rel_load"] - c["p_overshoot_max_rel_load"]) <= 1e-6


@pytest.mark.parametrize("method", ["vinewtonrsls", "vinewtonssls"])
def test_partial_opening_serial_and_parallel(tmp_path, method):
    """partial_opening (P1 u, the open zone moving along the crack) with the
    block preconditioner on 1 and 2 ranks: the direct solve's open zone and
    centre opening, the same Newton counts, <= 60 Krylov per Newton.  Newton
    starts each step from the last state (``-thm_predictor none``): on the
    line through the last two states, steps 3-7 need no Newton iteration at
    all, and at step 9, where the open zone moves, a round-off difference in
    the start decided whether the first iteration found the new active set
    (2 ranks: 9 or 10 Newton iterations from run to run, serial 9; the same
    open zone and opening), so the counts would compare the start, not the
    preconditioner."""
    common = ("-thm_partial_crack_size", 0.05, "-thm_fe_degree", 1, "-snes_type", method,
              "-thm_predictor", "none")
    _, ref = run_petthm("partial_opening", tmp_path / "direct", *common)
    newton = {}
    for n in (1, 2):
        out = tmp_path / f"block{n}"
        _, s = run_petthm("partial_opening", out, *common, *BLOCK, ranks=n)
        per = krylov_per_newton(out)
        print(method, n, "ranks: Newton", s["snes_iterations"], "Krylov per Newton max", max(per))
        assert s["status"] == "completed" and max(per) <= 60
        assert s["open_length"] == ref["open_length"] and s["nodes_open"] == ref["nodes_open"]
        assert abs(s["opening_centre"] - ref["opening_centre"]) <= 1e-8 * ref["opening_centre"]
        newton[n] = s["snes_iterations"]
    assert newton[1] == newton[2]


def test_ssls_crack_takes_a_gamg_threshold(tmp_path):
    """partial_opening with vinewtonssls on the size rule's block path (9 136
    unknowns): the crack scenes' recipe gives the glued elasticity's GAMG a
    graph threshold on its finest level (recipes.SSLS_CRACK_GAMG).  Measured
    7.4 Krylov per Newton against 15.9 without it (PETSc's unfiltered graph,
    threshold -1: the negative control; 3.26: 7.6 against 15.2), the same
    open zone and opening; vinewtonrsls is not given it."""
    common = ("-thm_partial_crack_size", 0.0125, "-thm_mesh_size", 25, "-thm_fe_degree", 1,
              "-thm_direct_max_unknowns", 0, "-snes_type", "vinewtonssls")
    _, s = run_petthm("partial_opening", tmp_path / "recipe", *common)
    _, c = run_petthm("partial_opening", tmp_path / "control", *common,
                      "-vi_fieldsplit_mech_contact_pc_gamg_threshold", -1)
    per = {k: r["ksp_iterations"] / r["snes_iterations"] for k, r in (("recipe", s), ("control", c))}
    print("Krylov per Newton", per)
    assert s["status"] == c["status"] == "completed"
    assert per["recipe"] <= 0.6 * per["control"]
    assert s["open_length"] == c["open_length"] and s["nodes_open"] == c["nodes_open"]
    assert abs(s["opening_centre"] - c["opening_centre"]) <= 1e-8 * c["opening_centre"]


def test_the_recipe_file_is_the_size_default():
    """options/solvers/block.opts and the recipe petthm proposes above
    -thm_direct_max_unknowns are the same options."""
    from petthm.solvers.recipes import BLOCK_RECIPE
    opts = {}
    for line in read_text(f"{ROOT}/options/solvers/block.opts").splitlines():
        line = line.split("#")[0].split()
        if line:
            opts[line[0].lstrip("-")] = line[1] if len(line) > 1 else ""
    assert opts == BLOCK_RECIPE


def test_large_problems_get_the_block_preconditioner(tmp_path):
    """Above -thm_direct_max_unknowns a scene with displacement proposes the
    block preconditioner (the summary's options say so); below it the
    direct solve; the user's own choice wins."""
    common = ("-thm_partial_crack_size", 0.05, "-thm_fe_degree", 1, "-thm_final_time", 0.2)
    _, small = run_petthm("partial_opening", tmp_path / "small", *common)
    _, large = run_petthm("partial_opening", tmp_path / "large", *common, "-thm_direct_max_unknowns", 100)
    _, mine = run_petthm("partial_opening", tmp_path / "mine", *common, "-thm_direct_max_unknowns", 100,
                         "-pc_type", "lu", "-ksp_type", "gmres")
    effective = {k: {o.lstrip("-"): v for o, v in s["provenance"]["options"].items()}
                 for k, s in (("small", small), ("large", large), ("mine", mine))}
    print({k: (v.get("pc_type"), v.get("ksp_type")) for k, v in effective.items()})
    assert effective["small"]["pc_type"] == "lu"
    assert effective["large"]["pc_type"] == "python" and effective["large"]["ksp_type"] == "fgmres"
    assert effective["mine"]["pc_type"] == "lu"
    assert small["opening_centre"] == pytest.approx(large["opening_centre"], rel=1e-8)


def test_a_scene_changes_the_block_recipe():
    """Above the size threshold the scene's changes go over BLOCK_RECIPE
    (Scene 3: the flow and heat fields as one split, first); below it nothing of the recipe is
    proposed."""
    from types import SimpleNamespace

    from petsc4py import PETSc

    from petthm.scenes import scene_class
    from petthm.solvers.recipes import BLOCK_RECIPE, solver_defaults_by_size

    def recipe_of(scene, degree, snes_type="vinewtonrsls", heat="auto"):
        run = SimpleNamespace(run=SimpleNamespace(fe_degree=degree), p=SimpleNamespace(heat_transport=heat))
        return scene_class(scene).block_recipe(run, snes_type)
    assert recipe_of("partial_opening", 1) == {}           # vinewtonrsls: no graph threshold
    ssls = recipe_of("partial_opening", 1, "vinewtonssls")
    assert ssls["vi_fieldsplit_mech_contact_pc_gamg_threshold"] == "0.05"
    order = recipe_of("inclined_penny", 2)
    # Scene 3: the flow and heat fields as one split, before the mechanics
    assert order["vi_groups"] == "flow_heat=pm+pf+Tf+Tm,mech=u+lam+tau"
    assert order["vi_fieldsplit_flow_heat_ksp_type"] == "gmres"
    # Scene 3's Newton and linear tolerances: tighter with the bound-preserving heat transport (its
    # balances follow the residual at which Newton stops), the contact scenes' with SUPG
    assert (order["snes_atol"], order["ksp_atol"]) == ("1e-10", "1e-12")
    supg = recipe_of("inclined_penny", 2, heat="supg")
    assert (supg["snes_atol"], supg["ksp_atol"]) == ("1e-9", "1e-10")
    big = solver_defaults_by_size({"pc_type": "lu"}, True, 10**6, 50000, order)
    assert big["vi_groups"] == order["vi_groups"] and big["pc_type"] == BLOCK_RECIPE["pc_type"]
    plain = solver_defaults_by_size({"pc_type": "lu"}, True, 10**6, 50000)
    assert plain["vi_groups"] == BLOCK_RECIPE["vi_groups"]
    assert solver_defaults_by_size({"pc_type": "lu"}, True, 10, 50000, order) == {"pc_type": "lu"}
    # Scene 3's Newton tolerance: 1e-10 on the block path (1e-9 with SUPG), the contact default
    # (1e-12) on the direct one
    direct = {"pc_type": "lu", "snes_atol": "1e-12"}
    assert solver_defaults_by_size(direct, True, 10**6, 50000, order)["snes_atol"] == "1e-10"
    assert solver_defaults_by_size(direct, True, 10**6, 50000, supg)["snes_atol"] == "1e-9"
    assert solver_defaults_by_size(direct, True, 10, 50000, order)["snes_atol"] == "1e-12"
    # Scene 2: the same tolerance on the block path

    def scene2_recipe(degree):
        return recipe_of("penny_impermeable", degree)
    scene2 = scene2_recipe(1)
    assert solver_defaults_by_size(direct, True, 10**6, 50000, scene2)["snes_atol"] == "1e-9"
    assert solver_defaults_by_size(direct, True, 10, 50000, scene2)["snes_atol"] == "1e-12"
    # {pf, Tf, Tm} one split after the mechanics, the glued elasticity by CG on its cycle:
    # BoomerAMG with P1 u where PETSc has hypre (else GAMG); P2 u its p-multigrid
    amg, cg = "vi_fieldsplit_mech_contact_pc_type", "vi_fieldsplit_mech_contact_ksp_type"
    assert scene2.get(amg) == ("hypre" if PETSc.Sys.hasExternalPackage("hypre") else None)
    for recipe in (scene2, scene2_recipe(2)):
        assert recipe[cg] == "cg" and recipe["vi_groups"].endswith("flow_heat=pf+Tf+Tm")
        assert recipe["vi_fieldsplit_flow_heat_ksp_type"] == "gmres"
    # P2 u: BoomerAMG on the P2 level itself where PETSc has hypre, else the p-multigrid
    hypre = PETSc.Sys.hasExternalPackage("hypre")
    assert scene2_recipe(2).get(amg) == ("hypre" if hypre else None)
    assert scene2_recipe(2).get("vi_fieldsplit_mech_contact_pmg") == ("0" if hypre else None)
    # and there without aggressive coarsening, by eight CG iterations, no contact-Schur term
    p2_changes = {"vi_fieldsplit_mech_contact_pc_hypre_boomeramg_agg_nl": "0",
                  "vi_fieldsplit_mech_contact_ksp_max_it": "8", "vi_contact_schur": "off"}
    without = dict.fromkeys(p2_changes) | {"vi_fieldsplit_mech_contact_ksp_max_it": "4"}  # GAMG p-multigrid
    assert all(scene2_recipe(2).get(k) == v for k, v in (p2_changes if hypre else without).items())
    assert all(scene2.get(k) != v for k, v in p2_changes.items())           # P1 u: unchanged
    scene3_p1 = recipe_of("inclined_penny", 1)
    assert scene3_p1.get(amg) == scene2.get(amg) and amg not in order
    # six CG iterations with P1 u (coarse Scene 3's levels), four with P2 u
    assert scene3_p1["vi_fieldsplit_mech_contact_ksp_max_it"] == "6"
    assert order["vi_fieldsplit_mech_contact_ksp_max_it"] == "4"
    assert amg not in solver_defaults_by_size(direct, True, 10, 50000, scene2)
    # 3D Terzaghi: the p-multigrid's P1 level without aggressive coarsening; Scene 3 keeps PETSc's
    from petthm.compat import GAMG_AGGRESSIVE_LEVELS
    assert recipe_of("terzaghi", 2) == {f"vi_fieldsplit_mech_contact_mg_coarse_{GAMG_AGGRESSIVE_LEVELS}": "0"}
    assert recipe_of("terzaghi", 1) == {}                  # P1 u: no p-multigrid, nothing to propose
    assert not any("_mg_coarse_" in k for r in (order, scene2, scene2_recipe(2)) for k in r)


@pytest.mark.first_pass_only
def test_scene3_flow_and_heat_split_keeps_the_coupling(tmp_path):
    """Scene 3 (coarse far field, a 12 m fracture mesh, P1 u) in 0.2-year
    steps under the block recipe with the scene's changes
    (``Scene.block_recipe``): {pm, pf, Tf, Tm} as one split before the
    mechanics needs clearly fewer Krylov iterations than the five splits of
    the fields' order, each by its AMG cycle (the control, which drops the
    coupling among the flow and heat fields; docs/solvers/index.md).
    Two ranks (block Jacobi with ILU(0) per rank in the one split) give the
    serial state."""
    common = ("-options_file", f"{ROOT}/options/scenes/inclined_penny_coarse.opts", "-thm_scene3_case", 2,
              "-thm_scene3_fracture_size", 12, "-thm_direct_max_unknowns", 0, "-thm_dt_initial", 6311390,
              "-ts_max_steps", 2)
    runs = {}
    for name, extra, ranks in (("split", (), 1),
                               ("control", ("-vi_groups", "Tf=Tf,Tm=Tm,mech=u+lam+tau,pm=pm,pf=pf"), 1),
                               ("split_2", (), 2)):
        proc, runs[name] = run_petthm("inclined_penny", tmp_path / name, *common, *extra, ranks=ranks,
                                      check=False)
        assert proc.returncode == 4 and runs[name]["status"] == "stopped", proc.stderr   # -ts_max_steps
    print({k: (s["steps"], s["rejected_steps"], s["snes_iterations"], s["ksp_iterations"])
           for k, s in runs.items()})
    for s in runs.values():
        assert s["steps"] == 2 and s["rejected_steps"] == 0        # the two steps asked for, none rejected
    assert runs["split"]["ksp_iterations"] <= 0.5 * runs["control"]["ksp_iterations"]
    serial, parallel = ((read_csv(tmp_path / n / "history.csv"))[-1]
                        for n in ("split", "split_2"))
    for key in ("injection_pressure", "production_temperature", "aperture_increase_max", "lam_min"):
        assert float(parallel[key]) == pytest.approx(float(serial[key]), rel=1e-6), key


def test_coupled_mms_takes_the_flow_and_heat_split(tmp_path):
    """The coupled MMS (every field: u, lam, pm, pf, Tf, Tm; 3D P1, open) on
    the block path takes Scene 3's recipe (``CoupledMMS.block_recipe``):
    few Krylov iterations per Newton iteration.  The control, BLOCK_RECIPE's
    five splits each by its AMG cycle, needs many times more (at 60 k
    unknowns every linear solve stopped at 500 iterations; docs/solvers/index.md)."""
    from petthm.solvers.recipes import BLOCK_RECIPE
    common = ("-thm_coupled_mms_dim", 3, "-thm_fe_degree", 1, "-thm_coupled_mms_supg", 1,
              "-thm_mesh_size", 0.12, "-thm_final_time", 0.5, "-thm_direct_max_unknowns", 0)
    its = largest_krylov_per_newton(tmp_path, "coupled_mms", common,
                                    {"recipe": (), "control": ("-vi_groups", BLOCK_RECIPE["vi_groups"])})
    assert its["recipe"] <= 10
    assert its["control"] >= 4 * its["recipe"]


def test_scene2_p2_block_path_gives_the_direct_solution(tmp_path):
    """Scene 2 with P2 u (coarse: 57 k unknowns) on the size rule's block
    path: its glued elasticity by BoomerAMG on the P2 level where PETSc has
    hypre (``-vi_fieldsplit_mech_contact_pmg 0``).  Seven steps to
    1e4 s give the direct solve's injection pressure, production
    temperature and lam at the injector to 1e-8 (measured: 1.2e-10,
    1.5e-14, 3.7e-10; to 1e7 s: 3.5e-11, 1.8e-11, 1.4e-9).  Without hypre
    the recipe keeps the p-multigrid (``test_a_scene_changes_the_block_recipe``,
    ``test_p_multigrid_for_p2_displacement``), and PETSc's own LU took
    ~3 min for the direct run: skipped."""
    from petsc4py import PETSc
    if not PETSc.Sys.hasExternalPackage("hypre"):
        pytest.skip("PETSc without hypre: Scene 2's P2 recipe keeps the p-multigrid")
    common = ("-options_file", f"{ROOT}/options/scenes/penny_impermeable.opts", "-thm_fe_degree", 2,
              "-thm_scene2_fracture_size", 40, "-thm_scene2_well_size", 20, "-thm_final_time", 1e4)
    size = "-thm_direct_max_unknowns"
    _, block = run_petthm("penny_impermeable", tmp_path / "block", *common, size, 0)
    _, direct = run_petthm("penny_impermeable", tmp_path / "direct", *common, size, 10**8)
    assert block["status"] == direct["status"] == "completed" and block["steps"] == direct["steps"]
    used = block["provenance"]["options"]
    assert used.get("-vi_fieldsplit_mech_contact_pmg") == "0"
    assert used["-pc_type"] == "python" and direct["provenance"]["options"].get("-pc_type") != "python"
    keys = ("injection_pressure", "production_temperature", "lam_injector")
    worst = max(abs(block[k] - direct[k]) / abs(direct[k]) for k in keys)
    print(f"Scene 2 P2, block path against the direct solve: {worst:.1e}")
    assert worst <= 1e-8


@pytest.mark.slow
def test_scene2_p2_recipe_holds_the_count_at_long_steps(tmp_path):
    """Scene 2 with P2 u (coarse: 57 k unknowns) to 3e7 s, its steps
    growing to 1e7 s, on the size rule's block path where PETSc has hypre:
    the recipe's P2 changes (``recipes.P2_GLUED_AMG``: BoomerAMG without
    aggressive coarsening, eight CG iterations; ``-vi_contact_schur off``)
    against the recipe before them (the negative control).  Measured: 221
    against 428 Krylov iterations in 28 Newton iterations each, the same
    steps; ~200 s a run (docs/solvers/index.md)."""
    from petsc4py import PETSc
    if not PETSc.Sys.hasExternalPackage("hypre"):
        pytest.skip("PETSc without hypre: Scene 2's P2 recipe keeps the p-multigrid")
    common = ("-options_file", f"{ROOT}/options/scenes/penny_impermeable.opts", "-thm_fe_degree", 2,
              "-thm_scene2_fracture_size", 40, "-thm_scene2_well_size", 20, "-thm_direct_max_unknowns", 0,
              "-thm_dt_initial", 1e7, "-thm_final_time", 3e7)
    glued = "-vi_fieldsplit_mech_contact_"
    before = ("-vi_contact_schur", "all", glued + "pc_hypre_boomeramg_agg_nl", 1, glued + "ksp_max_it", 4)
    _, s = run_petthm("penny_impermeable", tmp_path / "recipe", *common)
    _, c = run_petthm("penny_impermeable", tmp_path / "control", *common, *before)
    per = {k: r["ksp_iterations"] / r["snes_iterations"] for k, r in (("recipe", s), ("control", c))}
    print("Krylov per Newton", per)
    assert s["status"] == c["status"] == "completed" and s["steps"] == c["steps"]
    assert s["rejected_steps"] == 0
    assert per["recipe"] <= 0.6 * per["control"]
    for key in ("injection_pressure", "production_temperature", "lam_injector"):
        assert s[key] == pytest.approx(c[key], rel=1e-7), key
