"""Options of named groups (petthm.params.read_named and named_options;
../shared/docs/reservoir.md section 2): a region's or a fracture's option
overrides the global one for that group alone, is read and checked as the
global one, and the check for unknown options knows them."""
import pytest

from conftest import _only_options
from petthm import params as P
from petthm.errors import InputError
from petthm.physics import materials as mt

ROCK = mt.group("Rock", mt.ELASTIC + ("rock_porosity",))
JOINT = mt.group("Fracture", mt.JOINT)


@pytest.fixture(autouse=True)
def _clean_options():
    yield
    _only_options()


def test_a_regions_option_overrides_the_global_one_for_that_region_alone():
    _only_options(thm_rock_youngs_modulus="20e9", thm_region_granite_rock_youngs_modulus="60e9",
                  thm_region_Shale_rock_porosity="0.2")
    p = P.read(ROCK)
    fields = ("rock_youngs_modulus", "rock_poisson_ratio", "rock_porosity")
    granite, shale = (P.read_named(p, fields, "region", n) for n in ("granite", "shale"))
    E = (p.rock_youngs_modulus, granite.rock_youngs_modulus, shale.rock_youngs_modulus)
    assert E == (20e9, 60e9, 20e9)
    assert (p.rock_porosity, granite.rock_porosity, shale.rock_porosity) == (0.0, 0.0, 0.2)
    assert granite.rock_poisson_ratio == shale.rock_poisson_ratio == p.rock_poisson_ratio


def test_a_fractures_option_drops_the_fracture_prefix():
    _only_options(thm_fracture_FaultA_aperture="2e-4")
    p = P.read(JOINT)
    a = P.read_named(p, ("fracture_aperture",), "fracture", "faulta", strip="fracture_")
    assert a.fracture_aperture == 2e-4 and p.fracture_aperture != 2e-4


def test_a_groups_value_is_checked_as_the_global_one_and_the_error_names_its_option():
    _only_options(thm_region_granite_rock_porosity="1.5")
    with pytest.raises(InputError, match=r"-thm_region_granite_rock_porosity = 1.5 - is outside .*\[0, 1\]"):
        P.read_named(P.read(ROCK), ("rock_porosity",), "region", "granite")
    _only_options(thm_region_granite_rock_porosity="much")
    with pytest.raises(InputError, match=r"option -thm_region_granite_rock_porosity: cannot read 'much'"):
        P.read_named(P.read(ROCK), ("rock_porosity",), "region", "granite")


def test_the_unknown_option_check_knows_the_groups_options_and_suggests_them():
    names = P.named_options(ROCK, ("rock_youngs_modulus", "rock_porosity"), "region", ["Granite", "shale"])
    assert names == {"thm_region_granite_rock_youngs_modulus", "thm_region_shale_rock_youngs_modulus",
                     "thm_region_granite_rock_porosity", "thm_region_shale_rock_porosity"}
    _only_options(thm_region_GRANITE_rock_porosity="0.1")
    P.check_unknown_thm_options([ROCK], extra=names)
    _only_options(thm_region_granite_rock_porosty="0.1")
    with pytest.raises(InputError, match=r"unknown option -thm_region_granite_rock_porosty "
                                         r"\(did you mean -thm_region_granite_rock_porosity\?\)"):
        P.check_unknown_thm_options([ROCK], extra=names)
    _only_options(thm_region_basalt_rock_porosity="0.1")               # a group the mesh does not have
    with pytest.raises(InputError, match="unknown option -thm_region_basalt_rock_porosity"):
        P.check_unknown_thm_options([ROCK], extra=names)
