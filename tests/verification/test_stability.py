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
from verification_report import STABILITY, stability_row  # noqa: E402

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
