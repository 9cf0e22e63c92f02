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
    ta0 = [r["time"] for r in a]; tb0 = [r["time"] for r in b]
    same_path = ta0 == tb0
    if not same_path:                       # different step paths: compare the final states only
        a, b, n = a[-1:], b[-1:], 1
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
    return out, same_path, len(ta0), len(tb0)
if __name__ == "__main__":
    out, same, na, nb = compare(sys.argv[1], sys.argv[2])
    print("same times:", same, na, nb)
    for k, v in sorted(out.items(), key=lambda kv: -kv[1]):
        print(f"  {k:30s} {v:.2e}")
