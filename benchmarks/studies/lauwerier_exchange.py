"""``lauwerier`` with the three wall heat-exchange modes: equilibrium (Tm = Tf
on the walls, the analytical solution's assumption), nusselt (hw = 7.54
lambda_f / (2a)) and a given hw; reports each run's error against Lauwerier
and its production-temperature difference from the equilibrium run.

    python benchmarks/studies/lauwerier_exchange.py [--out output/lauwerier_exchange] [--hw 100] [-- OPTIONS]

Reads only the runs' summary.json / history.csv; writes exchange.csv and exchange.md."""
from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import numpy as np
from study_tables import ROOT, markdown, read_history, run_petthm, write_csv, write_markdown  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "output", "lauwerier_exchange"))
    ap.add_argument("--hw", default="100")
    ap.add_argument("extra", nargs="*")
    a = ap.parse_args()
    modes = ["equilibrium", "nusselt", a.hw]
    hist, summ = {}, {}
    for m in modes:
        d = os.path.join(a.out, f"runs/{m}")
        summ[m] = run_petthm("lauwerier", d, "-thm_fracture_heat_exchange", m, *a.extra)
        h = read_history(d)
        hist[m] = (h["time"], h["production_temperature"])
    t0, T0 = hist["equilibrium"]
    out = []
    for m in modes:
        t, T = hist[m]
        dT = np.interp(t0, t, T) - T0
        sel = t0 >= 1e6
        e = summ[m]["error"]
        out.append({"exchange": m, "outlet_error_vs_lauwerier_K": round(80 * e["outlet_max_rel_t_ge_1e6"], 4),
                    "max_dT_prod_vs_equilibrium_K_t_ge_1e6": round(float(np.abs(dT[sel]).max()), 4),
                    "dT_prod_vs_equilibrium_K_at_1e8": round(float(dT[-1]), 4),
                    "energy_balance_max": summ[m]["balance_max"]["energy_balance"],
                    "wall_s": round(summ[m]["wall_time"]["total"], 1)})
    os.makedirs(a.out, exist_ok=True)
    write_csv(os.path.join(a.out, "exchange.csv"), out)
    md = markdown([("exchange", "exchange", ""), ("outlet error vs Lauwerier, t >= 1e6 s (K)",
                    "outlet_error_vs_lauwerier_K", ""),
                   ("max abs T_prod - T_prod(equilibrium), t >= 1e6 s (K)",
                    "max_dT_prod_vs_equilibrium_K_t_ge_1e6", ""),
                   ("at 1e8 s (K)", "dT_prod_vs_equilibrium_K_at_1e8", ""),
                   ("energy balance", "energy_balance_max", ".1e"),
                   ("wall (s)", "wall_s", "")], out)
    write_markdown(os.path.join(a.out, "exchange.md"), "lauwerier: wall heat-exchange modes", md)
    print(md)


if __name__ == "__main__":
    main()
