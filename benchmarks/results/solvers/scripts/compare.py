import csv, sys, numpy as np
SKIP = {"step", "time", "dt", "snes_its", "ksp_its", "wall"}
def load(d):
    rows = list(csv.DictReader(open(d + "/history.csv")))
    return rows
def compare(da, db):
    """max over monitor columns of max_steps |a-b| / max_steps |b| (column scale); per-column dict."""
    a, b = load(da), load(db)
    out = {}
    n = min(len(a), len(b))
    for k in a[0]:
        if k in SKIP or k not in b[0]:
            continue
        try:
            x = np.array([float(r[k]) if r[k] != "" else np.nan for r in a[:n]])
            y = np.array([float(r[k]) if r[k] != "" else np.nan for r in b[:n]])
        except ValueError:
            continue
        m = ~(np.isnan(x) | np.isnan(y))
        if not m.any():
            continue
        scale = np.max(np.abs(y[m]))
        diff = np.max(np.abs(x[m] - y[m]))
        out[k] = diff / scale if scale > 0 else diff
    ta = np.array([float(r["time"]) for r in a]); tb = np.array([float(r["time"]) for r in b])
    same_t = len(a) == len(b) and np.allclose(ta, tb, rtol=1e-12, atol=0)
    return out, same_t, len(a), len(b)
if __name__ == "__main__":
    out, same, na, nb = compare(sys.argv[1], sys.argv[2])
    print("same times:", same, na, nb)
    for k, v in sorted(out.items(), key=lambda kv: -kv[1]):
        print(f"  {k:30s} {v:.2e}")
