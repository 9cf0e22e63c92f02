"""Orderings of non-negative integer keys (no physics here), by whichever of
two sorts is fast with the numpy at hand:

* where numpy sorts int64 with SIMD (x86-simd-sort: numpy >= 1.25 on
  AVX-512, >= 2.0 on AVX2 too), one ``np.sort`` of each key with its
  position packed into the low bits;
* otherwise a least-significant-digit radix sort: one stable
  ``np.argsort`` per 16-bit digit, which numpy does by counting (its radix
  sort for 16-bit types), O(n) per digit.

Measured on this machine (manual, performance), 0.42 M / 3.5 M
distinct keys: numpy 1.24 (Debian's, scalar int64 sorts) radix 10 / 170
ms against 22 / 250 ms for ``np.argsort``; numpy 1.26 on AVX-512 the packed
sort 4.0 / 38 ms against radix 11 / 167 ms and ``np.argsort`` 8.6 / 140 ms.
"""
from __future__ import annotations

import numpy as np

DIGIT = 16


def _simd_sort() -> bool:
    """Whether this numpy sorts int64 with SIMD instructions on this CPU."""
    try:
        version = tuple(int(x) for x in np.__version__.split(".")[:2])
        try:
            from numpy._core._multiarray_umath import __cpu_features__ as cpu
        except ImportError:
            from numpy.core._multiarray_umath import __cpu_features__ as cpu
    except (ImportError, ValueError):
        return False
    if version >= (2, 0):
        return bool(cpu.get("AVX512_SKX") or cpu.get("AVX2"))
    return version >= (1, 25) and bool(cpu.get("AVX512_SKX"))


SIMD_SORT = _simd_sort()


def key_order(keys: np.ndarray, packed: bool | None = None, overwrite: bool = False,
              counting: np.ndarray | None = None) -> np.ndarray:
    """The stable permutation that sorts the non-negative integer ``keys``
    (1-D): ``keys[key_order(keys)]`` is ascending, equal keys in their
    original order.  ``packed``: sort the keys with their positions packed
    into the low bits (where they fit in 63 bits) rather than by radix;
    default: where numpy's sort is SIMD (``SIMD_SORT``).  ``overwrite``:
    int64 ``keys`` may be overwritten (the packed sort then needs no copy);
    ``counting``: ``np.arange(keys.size)``, when the caller has it (large
    sorts are bound by fresh memory)."""
    keys = np.asarray(keys)
    if keys.size < 2:
        return np.arange(keys.size)
    if keys.min() < 0:
        raise ValueError("radix.key_order: negative key")
    bits = int(keys.size - 1).bit_length()
    if (SIMD_SORT if packed is None else packed) and int(keys.max()) < 1 << (63 - bits):
        own = overwrite and keys.dtype == np.int64 and keys.flags.writeable and keys.flags.c_contiguous
        packed_keys = keys if own else keys.astype(np.int64)
        packed_keys <<= bits
        packed_keys |= np.arange(keys.size) if counting is None else counting
        packed_keys.sort()
        packed_keys &= (1 << bits) - 1
        return packed_keys
    npass = max(1, -(-int(keys.max()).bit_length() // DIGIT))
    shifted = np.empty_like(keys)                                   # one buffer for every digit
    digits = np.empty((npass, keys.size), np.uint16)
    for d in range(npass):
        np.right_shift(keys, DIGIT * d, out=shifted)
        digits[d] = shifted                                         # its low 16 bits
    del shifted
    order = np.argsort(digits[0], kind="stable")                     # by counting
    for d in digits[1:]:
        order = order[np.argsort(d[order], kind="stable")]
    return order


def unique_ids(keys: np.ndarray) -> tuple[np.ndarray, int]:
    """Ids 0 .. count-1 of non-negative integer ``keys`` in key order (equal
    keys, equal ids), and count: ``np.unique(keys, return_inverse=True)[1]``
    and its number of values."""
    keys = np.asarray(keys).reshape(-1)
    if not keys.size:
        return np.zeros(0, np.intp), 0
    order = key_order(keys)
    sk = keys[order]
    new = np.empty(keys.size, np.intp)
    new[0] = 0
    np.not_equal(sk[1:], sk[:-1], out=new[1:])
    rank = np.cumsum(new)
    ids = np.empty(keys.size, np.intp)
    ids[order] = rank
    return ids, int(rank[-1]) + 1
