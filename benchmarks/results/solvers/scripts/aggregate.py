import csv, json, os, shutil, sys
import numpy as np
sys.path.insert(0, "/tmp/mi")
from compare import compare
RUNS = os.environ.get("RUNS_DIR", "/tmp/mi/runs_ccfb2cd")
TAG = os.environ.get("TAG", "")
RUNS_DEST = os.environ.get("RUNS_DEST", "runs")
OUT = "/work/main/benchmarks/results/solvers"

def row(case, label, d):
    cmd = open(os.path.join(d, "cmd.txt")).read().strip()
    t = open(os.path.join(d, "time.txt")).read().strip().splitlines()[-1].split() if os.path.exists(os.path.join(d, "time.txt")) else []
    r = {"case": case, "run": label, "solver": label.split("_")[0]}
    s = json.load(open(os.path.join(d, "summary.json")))
    rows = list(csv.DictReader(open(os.path.join(d, "history.csv"))))[1:]
    newton = np.array([float(x["snes_its"]) for x in rows]); kry = np.array([float(x["ksp_its"]) for x in rows])
    # the last row of a failed run repeats the final step with the failed attempt's counts: keep it (all work counts)
    per = kry[newton > 0] / newton[newton > 0]
    r.update(ranks=s["ranks"], cells=s["cells"], unknowns=sum(s["dofs"].values()),
             dofs=" ".join(f"{k}={v}" for k, v in s["dofs"].items()),
             steps=s["steps"], rejected=s["rejected_steps"],
             newton=s["snes_iterations"], krylov=s["ksp_iterations"],
             newton_per_step=s["snes_iterations"] / max(s["steps"], 1),
             krylov_per_newton=s["ksp_iterations"] / max(s["snes_iterations"], 1),
             krylov_per_newton_step_mean=float(per.mean()) if len(per) else 0.0,
             krylov_per_newton_max=float(per.max()) if len(per) else 0.0,
             pc_setups=s.get("solver_costs", {}).get("PCSetUp", {}).get("count", 0),
             pc_setup_s=s.get("solver_costs", {}).get("PCSetUp", {}).get("time", 0.0),
             ksp_solve_s=s.get("solver_costs", {}).get("KSPSolve", {}).get("time", 0.0),
             wall_s=s["wall_time"]["total"], elapsed_s=float(t[0]) if t else float("nan"),
             peak_mb_rank=s.get("peak_memory_mb", {}).get("max_rank", 0.0),
             peak_mb_total=s.get("peak_memory_mb", {}).get("total", 0.0),
             time_maxrss_mb=float(t[1]) / 1024 if len(t) > 1 else float("nan"),
             status=s["status"], reason=s.get("reason", ""), final_time=s.get("final_time", ""), command=cmd)
    return r

EXTRA = {"": [("fracture_inflation", "block_L1", "diag_fi_reuse/fi_direct_L1_again"),
              ("fracture_inflation", "block_L1", "diag_fi_reuse/fi_direct_L1_reuse_off"),
              ("fracture_inflation", "block_L3", "diag_direct_more/fi_direct_L3"),
              ("partial_opening_ssls", "block_L3", "diag_direct_more/po_ssls_direct_L3")],
         "_ccfb2cd": [("terzaghi3d", "block_L3", "diag_direct_L3/terzaghi3d_direct_L3"),
                      ("penny_impermeable", "block_L3", "diag_more/penny_direct_L3_forced"),
                      ("partial_opening_rsls", "block_L3", "diag_direct_L3/po_rsls_direct_L3"),
                      ("partial_opening_ssls", "block_L2", "diag_partial_opening_ssls/direct_L2"),
                      ("fracture_inflation", "block_L2", "diag_more/fi_direct_L2"),
                      ("fracture_inflation", "block_L3", "diag_direct_L3/fi_direct_L3")]}


def main():
    allrows = []
    for case in sorted(os.listdir(RUNS)):
        for label in sorted(os.listdir(os.path.join(RUNS, case))):
            d = os.path.join(RUNS, case, label)
            if not os.path.exists(os.path.join(d, "summary.json")):
                continue
            allrows.append(row(case, label, d))
            dst = os.path.join(OUT, RUNS_DEST, case, label); os.makedirs(dst, exist_ok=True)
            for f in ("summary.json", "history.csv", "cmd.txt", "log.txt", "time.txt"):
                if os.path.exists(os.path.join(d, f)):
                    shutil.copy(os.path.join(d, f), dst)
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(OUT, f"mesh_independence{TAG}.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(allrows[0])); w.writeheader(); w.writerows(allrows)
    # agreement
    agr = []
    for case in sorted(os.listdir(RUNS)):
        ref = [l for l in os.listdir(os.path.join(RUNS, case)) if l.startswith("direct")]
        for r in ref:
            for l in sorted(os.listdir(os.path.join(RUNS, case))):
                if l.startswith("block") and l.endswith(r.split("_")[1]) or (case == "weak_penny" and l.startswith("block")):
                    a, b = os.path.join(RUNS, case, l), os.path.join(RUNS, case, r)
                    if not (os.path.exists(a + "/history.csv") and os.path.exists(b + "/history.csv")):
                        continue
                    out, same, na, nb = compare(a, b)
                    agr.append(dict(case=case, block=l, direct=r, same_times=same, rows=f"{na}/{nb}" + ("" if same else " (final rows compared)"),
                                    **{k: f"{v:.1e}" for k, v in out.items()}))
    for case, l, r in EXTRA.get(TAG, []):
        a, b = os.path.join(RUNS, case, l), os.path.join(RUNS, r)
        out, same, na, nb = compare(a, b)
        agr.append(dict(case=case, block=l, direct=r, same_times=same, rows=f"{na}/{nb}" + ("" if same else " (final rows compared)"),
                        **{k: f"{v:.1e}" for k, v in out.items()}))
    with open(os.path.join(OUT, f"direct_agreement{TAG}.json"), "w") as f:
        json.dump(agr, f, indent=1)
    for a in agr: print(a)

main()
