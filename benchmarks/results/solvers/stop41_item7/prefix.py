"""Krylov per Newton over the first N steps of several runs' logs (the same step
sequence on every level: compare a run still going with finished ones).
  python prefix.py N out1.txt out2.txt ..."""
import re
import sys

n = int(sys.argv[1])
for path in sys.argv[2:]:
    st = [(float(t), int(a), int(b)) for t, a, b in
          re.findall(r"t = (\S+) s\s+dt = \S+ s\s+newton\s+(\d+)\s+krylov\s+(\d+)", open(path).read())][:n]
    late = [b / a for t, a, b in st if t > 1e7 and a]
    print(f"{path}: steps {len(st)} to t = {st[-1][0]:.4g} s, Newton {sum(a for _, a, _ in st)}, "
          f"Krylov {sum(b for _, _, b in st)}, per Newton {sum(b for *_, b in st) / sum(a for _, a, _ in st):.2f}, "
          f"largest in a step {max(b / a for _, a, b in st if a):.1f}, "
          f"mean per step at t > 1e7 s {sum(late) / max(1, len(late)):.1f}")
