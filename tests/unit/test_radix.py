"""``petthm.discretisation.radix``: the radix orderings equal numpy's stable sorts."""
import numpy as np
import pytest

from petthm.discretisation.radix import key_order, unique_ids


@pytest.mark.parametrize("packed", [False, True])
@pytest.mark.parametrize("top", [1, 7, 2**16, 2**16 + 1, 2**28, 2**40, 2**62])
def test_key_order_is_the_stable_argsort(top, packed):
    """Both sorts (the packed one falls back to radix above 63 bits)."""
    rng = np.random.default_rng(top % 97)
    keys = rng.integers(0, top, 5001)
    keys[::7] = keys[0]                                  # ties: kept in their order
    assert np.array_equal(key_order(keys, packed=packed), np.argsort(keys, kind="stable"))
    ids, count = unique_ids(keys)
    u, inv = np.unique(keys, return_inverse=True)
    assert count == u.size and np.array_equal(ids, inv.reshape(-1))


def test_a_digit_left_out_would_show():
    """Negative control: keys that differ only above the low 16 bits are
    ordered by the second digit (one digit alone leaves them as given)."""
    keys = np.array([3 << 16, 1 << 16, 2 << 16])
    assert list(key_order(keys)) == [1, 2, 0]
    assert list(np.argsort(keys.astype(np.uint16), kind="stable")) == [0, 1, 2]


def test_small_and_negative_inputs():
    assert key_order(np.array([], np.int64)).size == 0
    assert unique_ids(np.array([], np.int64))[1] == 0
    assert list(key_order(np.array([5]))) == [0]
    with pytest.raises(ValueError):
        key_order(np.array([1, -1]))
