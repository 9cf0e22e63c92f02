"""Krylov iterations per Newton iteration from the logs of coupled_mms_levels.sh (or any petthm
log): per run, unknowns, steps, rejected, Newton, Krylov, their ratio, the largest ratio in one
step, wall time and the linear solves that did not converge.  Usage: levels_table.py LOG..."""
import re
import sys


def counts(text: str) -> dict:
    """A petthm log's unknowns, (steps, rejected, wall) when it completed, Newton and Krylov
    iterations, the largest Krylov per Newton in one step and the linear solves that failed."""
    dofs = re.search(r"dofs (.*)", text)
    steps = re.findall(r"newton\s+(\d+)\s+krylov\s+(\d+)", text)
    done = re.search(r"in (\d+) steps \((\d+) rejected\), ([\d.]+) s", text)
    return dict(n=sum(int(v) for v in re.findall(r"=(\d+)", dofs.group(1))) if dofs else 0,
                done=done.groups() if done else None,
                newton=sum(int(n) for n, _ in steps), krylov=sum(int(k) for _, k in steps),
                worst=max((int(k) / int(n) for n, k in steps if int(n)), default=float("nan")),
                bad=text.count("Linear solve did not converge"))


def summary(path):
    c = counts(open(path).read())
    steps, rejected, wall = c["done"] or ("-", "-", "-")
    return (f"| {path.split('/')[-1]} | {c['n']} | {steps} | {rejected} | {c['newton']} | {c['krylov']} | "
            f"{c['krylov'] / max(c['newton'], 1):.2f} | {c['worst']:.1f} | {wall} | {c['bad']} |")


if __name__ == "__main__":
    print("| run | unknowns | steps | rejected | Newton | Krylov | Krylov/Newton | largest in a step | wall s "
          "| not converged |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for p in sys.argv[1:]:
        print(summary(p))
