"""The stiff and extreme cases of the verification and stability report
(issue 16 item 6; ``scripts/verification_report.py``'s ``STABILITY``) that
no other test runs: each completes (or stops cleanly where that is the
expected outcome) with a finite history, Tf within its bounds where the
case requires it, and the case's own checks."""
import os
import sys

import pytest

from conftest import ROOT, read_text

sys.path.insert(0, os.path.join(ROOT, "scripts"))
from verification_report import STABILITY, TRACTION_RECORDS, stability_row, traction_section  # noqa: E402

HERE = "tests/verification/test_stability.py"


@pytest.mark.parametrize("case", [c for c in STABILITY if c.test == HERE], ids=lambda c: c.name[:40])
def test_stiff_and_extreme_case(tmp_path, case):
    row = stability_row(case, str(tmp_path))
    print(row)
    assert row["passed"], row


def test_every_stability_case_is_a_test():
    """The report's cases that name another test point at one that exists."""
    for case in STABILITY:
        path, _, name = case.test.partition("::")
        text = read_text(os.path.join(ROOT, path))
        assert not name or f"def {name}(" in text, case.test


def test_the_traction_section_judges_each_refinement(tmp_path):
    """The report's contact-traction table (from benchmarks/records/): one
    row per mesh, each refinement "met" where the recovered traction's slope
    reaches the bound and "not met" where it does not."""
    import csv
    assert len([r for r in traction_section() if r.startswith("| 3D") or r.startswith("|  |")]) >= 6
    degree, name, least = TRACTION_RECORDS[0]
    with open(os.path.join(ROOT, "benchmarks", "records", name), newline="") as f:
        data = list(csv.DictReader(f))
    verdicts = {}
    for slope in (least - 0.01, least + 0.01):
        data[-1]["lam_recovered_slope"] = str(slope)
        with open(tmp_path / name, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(data[0]))
            w.writeheader()
            w.writerows(data)
        verdicts[slope] = [r for r in traction_section(str(tmp_path)) if r.startswith("|")][1 + len(data)]
    assert verdicts[least - 0.01].endswith("| not met |") and verdicts[least + 0.01].endswith("| met |")
