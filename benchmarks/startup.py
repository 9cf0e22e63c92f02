"""Start-up of small runs (issue 16 item 4): seconds from process start to
the first time step.

Runs ``python -m petthm SCENE -ts_monitor -ts_max_steps 1`` for each scene
(default options, one rank, no launcher: an MPI singleton) ``--repeat``
times, the scenes alternated so that the machine's load is shared alike, and
reads the time at which each line of interest reaches the pipe:

* ``start``: PETSc's monitor line ``0 TS ...`` -- the time loop begins (the
  mesh, set-up and initial output are done);
* ``first``: ``1 TS ...`` -- the first step is done;
* ``exit``: the process has ended.

A bare ``python -c "from petsc4py import PETSc"`` is timed alongside as the
floor, plain and with the singleton settings ``python -m petthm`` makes.
Writes ``startup.csv`` (one row per run) and ``startup.md`` (medians per
scene) to ``--out``.

    python benchmarks/startup.py [--scenes terzaghi,heat_erfc,...] [--repeat 7]
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from petthm.__main__ import isolate_singleton

SCENES = ("terzaghi", "heat_erfc", "fracture_flow_patch", "mandel", "contact_patch",
          "lauwerier")
MARKS = {"start": "0 TS", "first": "1 TS"}
#: the bare import, as a plain singleton and as ``python -m petthm`` sets one up (petthm.__main__)
_SINGLETON: dict[str, str] = {}
isolate_singleton(_SINGLETON)
BARE = {"import petsc4py.PETSc": {}, "import petsc4py.PETSc, isolated ob1 singleton": _SINGLETON}


def time_run(argv: list[str], **extra: str) -> dict[str, float]:
    """Seconds from starting ``argv`` (environment plus ``extra``) to each
    mark's first line and to exit."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env.update(extra)
    env["PYTHONUNBUFFERED"] = "1"
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=env)
    seen: dict[str, float] = {}
    for line in proc.stdout:
        for key, head in MARKS.items():
            if key not in seen and line.lstrip().startswith(head):
                seen[key] = time.perf_counter() - t0
    if proc.wait() not in (0, 4):                    # 4: stopped by -ts_max_steps, as asked
        raise SystemExit(f"startup.py: {' '.join(argv)} failed (exit {proc.returncode})")
    seen["exit"] = time.perf_counter() - t0
    return seen


def cells(out: Path) -> int:
    return int(json.loads((out / "summary.json").read_text()).get("cells", 0))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent.parent / "output" / "startup"))
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    scenes = [s for s in a.scenes.split(",") if s]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes:                      # once each: byte-code written, not timed
            time_run([sys.executable, "-m", "petthm", scene, "-ts_max_steps", "1",
                      "-thm_output_dir", f"{tmp}/{scene}", "-thm_overwrite"])
        for r in range(a.repeat):
            for case, extra in BARE.items():
                t = time_run([sys.executable, "-c", "from petsc4py import PETSc"], **extra)
                rows.append({"case": case, "repeat": r, "start": "", "first": "", "exit": f"{t['exit']:.3f}"})
            for scene in scenes:
                t = time_run([sys.executable, "-m", "petthm", scene, "-ts_monitor", "-ts_max_steps", "1",
                              "-thm_output_dir", f"{tmp}/{scene}", "-thm_overwrite"])
                times = {k: f"{t[k]:.3f}" for k in ("start", "first", "exit")}
                rows.append({"case": scene, "repeat": r, **times})
                print(scene, r, t, flush=True)
        ncells = {s: cells(Path(tmp) / s) for s in scenes}
    with open(out / "startup.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["case", "repeat", "start", "first", "exit"])
        w.writeheader()
        w.writerows(rows)
    lines = [f"# Start-up: process start to the first time step ({a.repeat} runs each, alternated; medians)",
             "", f"`python benchmarks/startup.py --scenes {a.scenes} --repeat {a.repeat}`", "",
             "| case | cells | to the first step (s) | first step done (s) | exit (s) |",
             "|---|---|---|---|---|"]
    for case in list(BARE) + scenes:
        sel = [x for x in rows if x["case"] == case]
        med = {k: (f"{statistics.median(float(x[k]) for x in sel):.3f}" if sel[0][k] else "-")
               for k in ("start", "first", "exit")}
        lines.append(f"| {case} | {ncells.get(case, '-')} | {med['start']} | {med['first']} "
                     f"| {med['exit']} |")
    (out / "startup.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
