"""The EGS doublet's figure (README.md): production temperature and thermal
power over the 20 years, and each fracture's share of the injected water.

    python examples/egs_doublet/plot.py [output/egs_doublet] [examples/egs_doublet/egs_doublet.png]
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

YEAR = 3.15576e7


def main(run: str = "output/egs_doublet", figure: str = "examples/egs_doublet/egs_doublet.png") -> None:
    with open(f"{run}/history.csv") as f:
        rows = list(csv.DictReader(f))[1:]                # the rows after the initial state
    t = [float(r["time"]) / YEAR for r in rows]
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8), constrained_layout=True)
    a.plot(t, [float(r["well_prod_temperature"]) for r in rows], color="C3")
    a.set_xlabel("time (years)")
    a.set_ylabel("production temperature (°C)", color="C3")
    power = a.twinx()
    power.plot(t, [float(r["well_prod_power"]) / 1e6 for r in rows], color="C0")
    power.set_ylabel("thermal power above 40 °C (MW)", color="C0")
    a.set_title("producer")
    for k in (k for k in rows[0] if k.startswith("well_inj_fracture_")):
        name = k[len("well_inj_fracture_"):-len("_rate")]
        b.plot(t, [float(r[k]) / float(r["well_inj_rate"]) for r in rows], label=name)
    b.set_xlabel("time (years)")
    b.set_ylabel("share of the injected water")
    b.set_title("injector: the rate at each fracture crossing")
    b.legend(title="fracture", ncol=2)
    fig.savefig(figure, dpi=110)
    print(f"wrote {figure}")


if __name__ == "__main__":
    main(*sys.argv[1:])
