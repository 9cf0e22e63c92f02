"""``scripts/scene3_study.py``: the two maxima of the aperture history (the
injection pressure's early one and the thermal one) on histories of known
shape."""
import os
import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, os.path.join(ROOT, "scripts"))
from scene3_study import aperture_maxima  # noqa: E402

YEARS = np.linspace(0.0, 30.0, 301)


def test_an_early_peak_then_a_thermal_maximum_before_30_years():
    h = 0.28 * np.exp(-((YEARS - 0.7) / 0.5) ** 2) + 0.27 * np.exp(-((YEARS - 16.8) / 8.0) ** 2) + 0.01
    m = aperture_maxima(YEARS, h)
    assert m["early"][1] == pytest.approx(0.7, abs=0.1) and m["early"][0] == pytest.approx(0.29, abs=0.01)
    assert m["thermal"][1] == pytest.approx(16.8, abs=0.1)
    assert m["thermal"][0] == pytest.approx(0.28, abs=0.01)


def test_an_early_peak_then_a_rise_to_30_years():
    h = 0.076 * np.exp(-((YEARS - 0.67) / 0.5) ** 2) + 0.07 + 0.0002 * YEARS
    m = aperture_maxima(YEARS, h)
    assert m["early"][1] == pytest.approx(0.7, abs=0.1)
    assert m["thermal"][1] == 30.0


def test_a_history_that_only_rises_has_a_thermal_maximum_alone():
    m = aperture_maxima(YEARS, 0.1 * (1 - np.exp(-YEARS / 5)))
    assert np.isnan(m["early"][0]) and m["thermal"] == (pytest.approx(0.1 * (1 - np.exp(-6))), 30.0)


def test_a_history_that_falls_after_its_early_peak_has_no_thermal_maximum():
    h = 0.3 * np.exp(-((YEARS - 0.7) / 0.5) ** 2) + 0.2 * np.exp(-YEARS / 10)
    m = aperture_maxima(YEARS, h)
    assert m["early"][1] == pytest.approx(0.7, abs=0.1) and np.isnan(m["thermal"][0])


def test_wiggles_below_the_prominence_are_not_an_early_peak():
    h = 0.1 * (1 - np.exp(-YEARS / 5)) + 1e-4 * np.sin(7 * YEARS)
    assert np.isnan(aperture_maxima(YEARS, h)["early"][0])
