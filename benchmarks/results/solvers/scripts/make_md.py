import csv, json, os, re
OUT = "/work/main/benchmarks/results/solvers"
TAG = os.environ.get("TAG", "")
NOTES = os.environ.get("NOTES", "/tmp/mi")
rows = list(csv.DictReader(open(f"{OUT}/mesh_independence{TAG}.csv")))
R = {(r["case"], r["run"]): r for r in rows}
agr = json.load(open(f"{OUT}/direct_agreement{TAG}.json"))
f = lambda x, p=1: f"{float(x):.{p}f}"

def lvl_opts(cmd):
    keys = ["-thm_mesh_size", "-thm_partial_crack_size", "-thm_scene2_fracture_size", "-thm_scene2_well_size", "-thm_terzaghi_width"]
    toks = cmd.split()
    out = []
    for k in keys:
        if k in toks:
            out.append(f"{k.replace('-thm_', '').replace('scene2_', '').replace('partial_', '')} {toks[len(toks) - 1 - toks[::-1].index(k) + 1]}")
    return ", ".join(out)

HDR = ("| run | level options | unknowns (total) | per field | steps (rejected) | Newton / step | Krylov / Newton (total ratio) | Krylov / Newton (mean of steps) | max Krylov / Newton (step) | wall (s) | peak MB / rank | status |\n"
       "|---|---|---|---|---|---|---|---|---|---|---|---|")
def line(r):
    return (f"| {r['run']} | {lvl_opts(r['command'])} | {r['unknowns']} | {r['dofs']} | {r['steps']} ({r['rejected']}) | {f(r['newton_per_step'],2)} | "
            f"{f(r['krylov_per_newton'])} | {f(r['krylov_per_newton_step_mean'])} | {f(r['krylov_per_newton_max'])} | {f(r['wall_s'])} | {f(r['peak_mb_rank'],0)} | {r['status']} |")

def table(case, labels):
    return "\n".join([HDR] + [line(R[(case, l)]) for l in labels if (case, l) in R])

def growth(case, a="block_L1", b="block_L3"):
    ra, rb = R[(case, a)], R[(case, b)]
    return (f"Unknowns x{int(rb['unknowns'])/int(ra['unknowns']):.2f} from level 1 to 3; Krylov / Newton (total ratio) "
            f"x{float(rb['krylov_per_newton'])/float(ra['krylov_per_newton']):.2f} ({f(ra['krylov_per_newton'])} -> {f(rb['krylov_per_newton'])}); "
            f"mean of per-step ratios x{float(rb['krylov_per_newton_step_mean'])/float(ra['krylov_per_newton_step_mean']):.2f}; "
            f"max per step x{float(rb['krylov_per_newton_max'])/float(ra['krylov_per_newton_max']):.2f}.")

def agree(case):
    out = []
    for a in agr:
        if a["case"] != case: continue
        cols = {k: v for k, v in a.items() if k not in ("case", "block", "direct", "same_times", "rows")}
        state = {k: v for k, v in cols.items() if "balance" not in k}
        bal = {k: v for k, v in cols.items() if "balance" in k}
        worst = max(state.items(), key=lambda kv: float(kv[1]))
        s = (f"* `{a['block']}` vs `{a['direct']}`: same step times {a['same_times']} ({a['rows']} history rows); largest relative "
             f"difference of the state columns {worst[1]} (`{worst[0]}`; all: " + ", ".join(f"{k} {v}" for k, v in state.items()) + ")")
        if bal:
            s += "; balance-error columns (themselves relative errors ~1e-8, so this is their noise): " + ", ".join(f"{k} {v}" for k, v in bal.items())
        out.append(s)
    return "\n".join(out)

md = [open(f"{NOTES}/md_head.md").read()]
for case, title in [("terzaghi3d", "1. terzaghi 3D (P2 u / P1 pm), `-thm_terzaghi_width 4`"),
                    ("partial_opening_rsls", "2a. partial_opening P1, vinewtonrsls"),
                    ("partial_opening_ssls", "2b. partial_opening P1, vinewtonssls"),
                    ("fracture_inflation", "3. fracture_inflation P1 (vinewtonrsls)"),
                    ("penny_impermeable", "4. penny_impermeable (Scene 2) P1")]:
    md.append(f"## {title}\n\n" + table(case, ["direct_L1", "block_L1", "block_L2", "block_L3"]) + "\n\n" + growth(case) +
              "\n\nDirect-solve agreement (level 1):\n\n" + agree(case) + "\n")
    if os.path.exists(f"{NOTES}/notes_{case}.md"):
        md.append(open(f"{NOTES}/notes_{case}.md").read())
md.append("## 5a. Weak scaling: terzaghi 3D, `-thm_mesh_size 0.7`, width grown with the rank count\n\n"
          + table("weak_terzaghi3d", ["direct_n1", "block_n1", "block_n2", "block_n4", "block_n8"]).replace("| run |", "| run (ranks) |")
          + "\n\n" + growth("weak_terzaghi3d", "block_n1", "block_n8").replace("level 1 to 3", "1 to 8 ranks") + "\n\nDirect-solve agreement (1 rank):\n\n" + agree("weak_terzaghi3d") + "\n")
md.append("## 5b. Scene 2 level (10, 5, 75) on 1, 2, 4 ranks (same mesh)\n\n"
          + table("weak_penny", ["direct_n1", "block_n1", "block_n2", "block_n4"])
          + "\n\nDirect-solve (1 rank) agreement of every rank count:\n\n" + agree("weak_penny") + "\n")
md.append(open(f"{NOTES}/md_tail.md").read())
open(f"{OUT}/mesh_independence{TAG}.md", "w").write("\n".join(md))
