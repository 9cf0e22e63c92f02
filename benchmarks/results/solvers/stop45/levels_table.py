"""Krylov iterations per Newton iteration from the logs of coupled_mms_levels.sh (or any petthm
log): per run, unknowns, steps, rejected, Newton, Krylov, their ratio, the largest ratio in one
step, wall time and the linear solves that did not converge.  Usage: levels_table.py LOG..."""
import re
import sys


def summary(path):
    text = open(path).read()
    dofs = sum(int(v) for v in re.findall(r"\w+=(\d+)", re.search(r"dofs (.*)", text).group(1)))
    steps = re.findall(r"newton\s+(\d+)\s+krylov\s+(\d+)", text)
    newton = sum(int(n) for n, _ in steps)
    krylov = sum(int(k) for _, k in steps)
    done = re.search(r"in (\d+) steps \((\d+) rejected\), ([\d.]+) s", text)
    worst = max((int(k) / int(n) for n, k in steps if int(n)), default=float("nan"))
    diverged = len(re.findall(r"Linear solve did not converge", text))
    return (f"| {path.split('/')[-1]} | {dofs} | {done.group(1) if done else '-'} | "
            f"{done.group(2) if done else '-'} | {newton} | {krylov} | {krylov / max(newton, 1):.2f} | "
            f"{worst:.1f} | {done.group(3) if done else '-'} | {diverged} |")


print("| run | unknowns | steps | rejected | Newton | Krylov | Krylov/Newton | largest in a step | wall s "
      "| not converged |")
print("|---|---|---|---|---|---|---|---|---|---|")
for p in sys.argv[1:]:
    print(summary(p))
