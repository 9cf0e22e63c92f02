"""The first rock layer of a layered mesh next to a fracture (issue 16 item
2): ``-thm_*_layer`` takes a thickness or ``auto``, 0.5 sqrt(kappa t) at the
scene's first output time."""
import math

import pytest

from petthm.errors import InputError
from petthm.scenes.fractured import AUTO_LAYER_FRACTION, FirstLayer, first_layer_option

parse = first_layer_option("thm_scene2_layer")


def test_auto_and_numbers_are_read():
    auto = parse(" Auto ")
    assert auto == FirstLayer(None) and str(auto) == "auto" and auto.layered
    assert parse("0.05") == FirstLayer(0.05) and parse(0.5).layered
    assert parse("0") == FirstLayer(0.0) and not parse("0").layered


@pytest.mark.parametrize("text", ["abc", "-1", "nan", "inf", ""])
def test_bad_values_name_the_option(text):
    with pytest.raises(InputError, match="option -thm_scene2_layer = .* is not auto or a thickness >= 0"):
        parse(text)


def test_auto_is_half_the_diffusion_length_and_a_number_stays_as_given():
    kappa, t = 1.2e-6, 1e4
    assert AUTO_LAYER_FRACTION == 0.5
    assert parse("auto").resolve(kappa, t) == pytest.approx(0.5 * math.sqrt(kappa * t), rel=1e-15)
    assert parse("auto").resolve(4 * kappa, t) == pytest.approx(2 * parse("auto").resolve(kappa, t))
    assert parse("0.3").resolve(kappa, t) == 0.3          # negative control: no sizing of a given value
