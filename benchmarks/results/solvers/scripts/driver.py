"""Sequential runner of the mesh-independence study (one petthm run at a time).
python driver.py CASE  -> runs the case's runs not yet done, into /tmp/mi/runs/CASE/LABEL."""
import os, shlex, subprocess, sys, time, json
ROOT = "/tmp/mi/src_09d8db7"
PY = "/work/main/.venv/bin/python"
RUNS = "/tmp/mi/runs_09d8db7"
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_mpi_yield_when_idle="1",
           OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
BLOCK = "-options_file options/solvers/block.opts"
TERZ = "-options_file options/scenes/terzaghi.opts -thm_terzaghi_dim 3 -thm_final_time 5"
PENNY = ("-options_file options/scenes/penny_impermeable.opts -thm_fe_degree 1 -thm_scene2_layer 2 "
         "-thm_scene2_layer_growth 2.5 -thm_final_time 1e5")
FI = "-options_file options/scenes/fracture_inflation.opts -thm_fe_degree 1"
CRACK_LEVELS = ["-thm_partial_crack_size 0.05 -thm_mesh_size 100",
                "-thm_partial_crack_size 0.025 -thm_mesh_size 50",
                "-thm_partial_crack_size 0.0125 -thm_mesh_size 25"]
PENNY_LEVELS = ["-thm_scene2_fracture_size 20 -thm_scene2_well_size 10 -thm_mesh_size 150",
                "-thm_scene2_fracture_size 10 -thm_scene2_well_size 5 -thm_mesh_size 75",
                "-thm_scene2_fracture_size 5 -thm_scene2_well_size 2.5 -thm_mesh_size 37.5"]
TERZ_LEVELS = [f"-thm_terzaghi_width 4 -thm_mesh_size {h}" for h in (1, 0.7, 0.47)]


def crack(scene, common):
    runs = [("direct_L1", scene, common + " " + CRACK_LEVELS[0], 1)]
    runs += [(f"block_L{k+1}", scene, common + " " + lv + " " + BLOCK, 1) for k, lv in enumerate(CRACK_LEVELS)]
    return runs

CASES = {
    "terzaghi3d": [("direct_L1", "terzaghi", TERZ + " " + TERZ_LEVELS[0], 1)]
                  + [(f"block_L{k+1}", "terzaghi", TERZ + " " + lv + " " + BLOCK, 1) for k, lv in enumerate(TERZ_LEVELS)],
    "partial_opening_rsls": crack("partial_opening", "-thm_fe_degree 1 -snes_type vinewtonrsls"),
    "partial_opening_ssls": crack("partial_opening", "-thm_fe_degree 1 -snes_type vinewtonssls"),
    "fracture_inflation": crack("fracture_inflation", FI),
    "penny_impermeable": [("direct_L1", "penny_impermeable", PENNY + " " + PENNY_LEVELS[0], 1)]
                  + [(f"block_L{k+1}", "penny_impermeable", PENNY + " " + lv + " " + BLOCK, 1) for k, lv in enumerate(PENNY_LEVELS)],
    "weak_terzaghi3d": [("direct_n1", "terzaghi", TERZ + " -thm_mesh_size 0.7 -thm_terzaghi_width 4", 1)]
                  + [(f"block_n{n}", "terzaghi", TERZ + f" -thm_mesh_size 0.7 -thm_terzaghi_width {w} " + BLOCK, n)
                     for n, w in ((1, 4), (2, 6.3), (4, 8.4), (8, 11.9))],
    "weak_penny": [("direct_n1", "penny_impermeable", PENNY + " " + PENNY_LEVELS[1], 1)]
                  + [(f"block_n{n}", "penny_impermeable", PENNY + " " + PENNY_LEVELS[1] + " " + BLOCK, n) for n in (1, 2, 4)],
    "diag_partial_opening_ssls": [("direct_L3", "partial_opening", "-thm_fe_degree 1 -snes_type vinewtonssls " + CRACK_LEVELS[2], 1),
                                  ("direct_L2", "partial_opening", "-thm_fe_degree 1 -snes_type vinewtonssls " + CRACK_LEVELS[1], 1)],
    "diag_linear_failures": [(f"fi_block_L{k+1}", "fracture_inflation", FI + " " + lv + " " + BLOCK + " -ksp_converged_reason -snes_converged_reason", 1) for k, lv in enumerate(CRACK_LEVELS)]
                  + [("po_ssls_block_L3", "partial_opening", "-thm_fe_degree 1 -snes_type vinewtonssls " + CRACK_LEVELS[2] + " " + BLOCK + " -ksp_converged_reason -snes_converged_reason", 1)]
                  + [("po_ssls_block_L2", "partial_opening", "-thm_fe_degree 1 -snes_type vinewtonssls " + CRACK_LEVELS[1] + " " + BLOCK + " -ksp_converged_reason -snes_converged_reason", 1)],
    "diag_direct_L3": [("terzaghi3d_direct_L3", "terzaghi", TERZ + " " + TERZ_LEVELS[2], 1),
                       ("penny_direct_L3", "penny_impermeable", PENNY + " " + PENNY_LEVELS[2], 1),
                       ("fi_direct_L3", "fracture_inflation", FI + " " + CRACK_LEVELS[2], 1),
                       ("po_rsls_direct_L3", "partial_opening", "-thm_fe_degree 1 -snes_type vinewtonrsls " + CRACK_LEVELS[2], 1)],
    "diag_more": [("penny_direct_L3_forced", "penny_impermeable", PENNY + " " + PENNY_LEVELS[2] + " -thm_direct_max_unknowns 10000000", 1),
                  ("fi_direct_L2", "fracture_inflation", FI + " " + CRACK_LEVELS[1], 1),
                  ("fi_direct_L3_reasons", "fracture_inflation", FI + " " + CRACK_LEVELS[2] + " -ksp_converged_reason -snes_converged_reason", 1)]
                  + [(f"penny_block_lag1_L{k+1}", "penny_impermeable", PENNY + " " + lv + " " + BLOCK + " -snes_lag_preconditioner 1", 1) for k, lv in enumerate(PENNY_LEVELS)],
    "diag_repeat": [("weak_penny_block_n2_again", "penny_impermeable", PENNY + " " + PENNY_LEVELS[1] + " " + BLOCK, 2),
                    ("weak_terzaghi_block_n2_again", "terzaghi", TERZ + " -thm_mesh_size 0.7 -thm_terzaghi_width 6.3 " + BLOCK, 2)],
    "diag_memory": [(f"fi_block_L3_T{T}", "fracture_inflation", FI + " " + CRACK_LEVELS[2] + f" -thm_final_time {T} " + BLOCK, 1) for T in (100, 400, 1000)]
                   + [(f"fi_direct_L3_T{T}", "fracture_inflation", FI + " " + CRACK_LEVELS[2] + f" -thm_final_time {T}", 1) for T in (100, 1000)]
                   + [(f"terzaghi_block_L1_T{T}", "terzaghi", TERZ + " " + TERZ_LEVELS[0] + f" -thm_final_time {T} " + BLOCK, 1) for T in (0.5, 20)],
    "diag_direct_more": [("po_ssls_direct_L3", "partial_opening", "-thm_fe_degree 1 -snes_type vinewtonssls " + CRACK_LEVELS[2], 1),
                         ("fi_direct_L3", "fracture_inflation", FI + " " + CRACK_LEVELS[2], 1),
                         ("terzaghi3d_block_L1_T0.5", "terzaghi", TERZ + " " + TERZ_LEVELS[0] + " -thm_final_time 0.5 " + BLOCK, 1),
                         ("fi_block_L3_T100", "fracture_inflation", FI + " " + CRACK_LEVELS[2] + " -thm_final_time 100 " + BLOCK, 1)],
    "diag_fi_reuse": [("fi_direct_L1_reuse_off", "fracture_inflation", FI + " " + CRACK_LEVELS[0] + " -thm_pc_reuse off", 1),
                      ("fi_direct_L1_again", "fracture_inflation", FI + " " + CRACK_LEVELS[0], 1)],
}


def main():
    case = sys.argv[1]
    only = sys.argv[2:]
    for label, scene, opts, n in CASES[case]:
        if only and label not in only:
            continue
        d = os.path.join(RUNS, case, label)
        if os.path.exists(os.path.join(d, "summary.json")) and not only:
            print(f"{case}/{label}: done already", flush=True)
            continue
        os.makedirs(d, exist_ok=True)
        cmd = [PY, "-m", "petthm", scene, *shlex.split(opts), "-thm_output_dir", d, "-thm_quiet"]
        if n > 1:
            cmd = ["mpiexec", "-n", str(n)] + cmd
        cmd = ["/usr/bin/time", "-f", "%e %M", "-o", os.path.join(d, "time.txt"), "timeout", "1200"] + cmd
        with open(os.path.join(d, "cmd.txt"), "w") as f:
            f.write(f"cd {ROOT} && " + " ".join(shlex.quote(c) for c in cmd) + "\n")
        t0 = time.time()
        with open(os.path.join(d, "log.txt"), "w") as log:
            p = subprocess.run(cmd, cwd=ROOT, env=ENV, stdout=log, stderr=subprocess.STDOUT)
        dt = time.time() - t0
        st = "?"
        try:
            s = json.load(open(os.path.join(d, "summary.json")))
            st = f"{s['status']} steps {s['steps']} snes {s['snes_iterations']} ksp {s['ksp_iterations']} dofs {s['dofs']}"
        except Exception as e:
            st = f"no summary ({e})"
        print(f"{case}/{label}: rc {p.returncode} {dt:.1f}s {st}", flush=True)


main()
