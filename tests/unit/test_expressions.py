"""Expressions of position in option values (petthm.expressions;
../shared/docs/reservoir.md section 2): what they compute, and that anything
outside the allowlist is an input error naming the option and the piece."""
import numpy as np
import pytest

from petthm.errors import InputError
from petthm.expressions import Expression, split_list

POINTS = np.array([[0.0, 1.0, -1000.0], [2.0, -3.0, -2500.0], [5.0, 0.5, 10.0]])


@pytest.mark.parametrize("text,expected", [
    ("2.5e7", lambda x, y, z: np.full_like(x, 2.5e7)),
    ("1e5+(-z)*9810", lambda x, y, z: 1e5 - z * 9810),
    ("10+0.03*(-z)", lambda x, y, z: 10 - 0.03 * z),
    ("-x**2+y/4", lambda x, y, z: -x ** 2 + y / 4),
    ("where(z<-2000,1,2)", lambda x, y, z: np.where(z < -2000, 1.0, 2.0)),
    ("min(x,y)+max(x,y)", lambda x, y, z: x + y),
    ("exp(x/10)*sqrt(abs(y))+sin(x)*cos(y)+log(1+x)", lambda x, y, z:
     np.exp(x / 10) * np.sqrt(np.abs(y)) + np.sin(x) * np.cos(y) + np.log(1 + x)),
    ("where(-3000<z<=-1000,z,0)", lambda x, y, z: np.where((z > -3000) & (z <= -1000), z, 0.0)),
    ("(x>=2)*1.5", lambda x, y, z: (x >= 2) * 1.5),
])
def test_expressions_compute_their_value_at_every_point(text, expected):
    e = Expression(text, "-thm_test")
    np.testing.assert_allclose(e(POINTS), expected(*POINTS.T), rtol=1e-15, atol=0)


def test_a_constant_expression_is_a_number_and_one_of_position_is_not():
    assert Expression("2*3+1", "-thm_a").constant and Expression("2*3+1", "-thm_a").value() == 7.0
    e = Expression("1+z", "-thm_b")
    assert not e.constant and e.symbols == {"z"}
    with pytest.raises(InputError, match=r"-thm_b.*a number is needed here, not a function of z"):
        e.value()


def test_two_dimensional_expressions_have_x_and_y_only():
    e = Expression("x+2*y", "-thm_c", dim=2)
    np.testing.assert_allclose(e(POINTS[:, :2]), POINTS[:, 0] + 2 * POINTS[:, 1])
    with pytest.raises(InputError, match=r"-thm_c = 'z\*2'.*the name 'z' is not accepted; accepted: numbers"):
        Expression("z*2", "-thm_c", dim=2)


@pytest.mark.parametrize("text,piece", [
    ("depth*2", "the name 'depth'"),
    ("__import__('os')", "the call"),
    ("x.__class__", "'x.__class__'"),
    ("'a'", "the constant 'a'"),
    ("True", "the constant True"),
    ("[x]", "'\\[x\\]'"),
    ("x if y else z", "'x if y else z'"),
    ("lambda: 1", "'lambda: 1'"),
    ("max(x)", "with 1 argument\\(s\\) \\(max takes 2\\)"),
    ("exp(x=1)", "the call 'exp\\(x=1\\)'"),
    ("sqrt", "the name 'sqrt' \\(a function"),
    ("x and y", "'x and y'"),
    ("x//2", "'x // 2'"),
    ("9" * 400, "the constant"),
])
def test_anything_outside_the_allowlist_is_refused_by_name(text, piece):
    with pytest.raises(InputError, match=f"option -thm_d = .*{piece}.*accepted: numbers"):
        Expression(text, "-thm_d")


def test_text_that_is_not_an_expression_and_values_that_are_not_finite_are_errors():
    with pytest.raises(InputError, match=r"-thm_e = '1\+\*2': not an expression \(numbers"):
        Expression("1+*2", "-thm_e")
    with pytest.raises(InputError, match=r"-thm_f = 'log\(z\)' is not finite at \(0, 1, -1000\)"):
        Expression("log(z)", "-thm_f")(POINTS)
    with pytest.raises(InputError, match=r"is not finite"):
        Expression("1/(x-5)", "-thm_g")(POINTS)


def test_a_list_splits_at_its_top_level_commas_only():
    assert split_list("where(z<0,1,2),3") == ["where(z<0,1,2)", "3"]
    assert split_list("1e7,2e7,max(x,y)") == ["1e7", "2e7", "max(x,y)"]
    assert split_list("5") == ["5"]
