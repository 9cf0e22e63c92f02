"""Issue 12 item 7, the small cases on the landed code (stop 41): each case's
direct solve on level 1 and the size rule's block path (BLOCK_RECIPE, which is options/solvers/block.opts, with the scene's block_recipe) on
three levels, one run at a time.
  SRC=/tmp/s41/src RUNS=/tmp/s41/runs python item7.py run [CASE ...]
  RUNS=/tmp/s41/runs python item7.py table > item7.md"""
import json, os, re, shlex, subprocess, sys, time
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
from compare import compare   # noqa: E402

SRC = os.environ.get("SRC", "/work/main")
RUNS = os.environ.get("RUNS", "/tmp/s41/runs")
ENV = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
BLOCK = "-thm_direct_max_unknowns 0"   # the size rule's block path: BLOCK_RECIPE (= block.opts) and the scene's recipe
CRACK = ["-thm_partial_crack_size 0.05 -thm_mesh_size 100", "-thm_partial_crack_size 0.025 -thm_mesh_size 50",
         "-thm_partial_crack_size 0.0125 -thm_mesh_size 25"]
TERZ = [f"-thm_terzaghi_width 4 -thm_mesh_size {h}" for h in (1, 0.7, 0.47)]
CASES = {   # case: (scene, common options, level options)
    "terzaghi3d": ("terzaghi", "-options_file options/scenes/terzaghi.opts -thm_terzaghi_dim 3 -thm_dt_max 50", TERZ),
    "partial_opening_rsls": ("partial_opening", "-options_file options/scenes/partial_opening.opts "
                             "-thm_fe_degree 1 -snes_type vinewtonrsls", CRACK),
    "partial_opening_ssls": ("partial_opening", "-options_file options/scenes/partial_opening.opts "
                             "-thm_fe_degree 1 -snes_type vinewtonssls", CRACK),
    "fracture_inflation": ("fracture_inflation", "-options_file options/scenes/fracture_inflation.opts "
                           "-thm_fe_degree 1", CRACK),
}


def runs_of(case):
    scene, common, levels = CASES[case]
    yield "direct_L1", scene, f"{common} {levels[0]}"
    for k, lv in enumerate(levels):
        yield f"block_L{k + 1}", scene, f"{common} {lv} {BLOCK}"


def run(case):
    for label, scene, opts in runs_of(case):
        d = os.path.join(RUNS, case, label)
        os.makedirs(d, exist_ok=True)
        cmd = ["/usr/bin/time", "-f", "%e %M", "-o", os.path.join(d, "time.txt"), sys.executable, "-m", "petthm",
               scene, *shlex.split(opts), "-ksp_converged_reason", "-thm_output_dir", d]
        with open(os.path.join(d, "cmd.txt"), "w") as f:
            f.write(f"cd {SRC} && " + " ".join(shlex.quote(c) for c in cmd) + "\n")
        t0 = time.time()
        with open(os.path.join(d, "log.txt"), "w") as log:
            rc = subprocess.run(cmd, cwd=SRC, env=ENV, stdout=log, stderr=subprocess.STDOUT).returncode
        print(f"{case}/{label}: rc {rc} {time.time() - t0:.1f} s", flush=True)


def row(case, label):
    d = os.path.join(RUNS, case, label)
    s = json.load(open(os.path.join(d, "summary.json")))
    log = open(os.path.join(d, "log.txt")).read()
    steps = [(int(n), int(k)) for n, k in re.findall(r"newton\s+(\d+)\s+krylov\s+(\d+)", log)]
    worst = max(k / n for n, k in steps if n)
    wall, rss = open(os.path.join(d, "time.txt")).read().split()[-2:]
    return dict(unknowns=sum(s["dofs"].values()), steps=s["steps"], rejected=s["rejected_steps"],
                newton=s["snes_iterations"], krylov=s["ksp_iterations"], failed=log.count("DIVERGED"),
                kn=s["ksp_iterations"] / max(1, s["snes_iterations"]), worst=worst, wall=float(wall),
                rss=int(rss) // 1024, status=s["status"])


def table():
    print("| case | run | status | unknowns | steps (rejected) | failed linear solves | Newton | Krylov "
          "| Krylov per Newton | largest in a step | wall (s) | peak RSS (MB) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for case in CASES:
        if not all(os.path.exists(os.path.join(RUNS, case, label, "summary.json")) for label, _, _ in runs_of(case)):
            print(f"| {case} | (not every run of this case is in {RUNS}: skipped) |||||||||||")
            continue
        got = {}
        for label, _, _ in runs_of(case):
            r = got[label] = row(case, label)
            print(f"| {case} | {label} | {r['status']} | {r['unknowns']} | {r['steps']} ({r['rejected']}) "
                  f"| {r['failed']} | {r['newton']} | {r['krylov']} | {r['kn']:.1f} | {r['worst']:.1f} "
                  f"| {r['wall']:.1f} | {r['rss']} |")
        b1, b3 = got["block_L1"], got["block_L3"]
        diff, same, _, _ = compare(os.path.join(RUNS, case, "block_L1"), os.path.join(RUNS, case, "direct_L1"))
        print(f"| {case} | **L3/L1** | unknowns x{b3['unknowns'] / b1['unknowns']:.1f} | Krylov per Newton "
              f"x{b3['kn'] / b1['kn']:.2f} | block_L1 vs direct_L1: same steps {same}, largest relative "
              f"difference {max(diff.values()):.1e} ({max(diff, key=diff.get)}) |||||||")


if __name__ == "__main__":
    if sys.argv[1] == "run":
        for c in sys.argv[2:] or CASES:
            run(c)
    else:
        table()
