"""The packed row flags of the numba kernels (``flic_cli/bitwords.py``) against numpy's packbits."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from flic_cli.bitwords import pack, trailing_zeros


@njit(cache=False)
def _pack(flags: np.ndarray, words: np.ndarray) -> None:
    pack(flags, words)


@njit(cache=False)
def _set_bits(words: np.ndarray) -> np.ndarray:
    """Positions of the set bits, visited as the kernels visit them."""
    out = np.empty(64 * words.size, dtype=np.int64)
    n = 0
    for k in range(words.size):
        bits = words[k]
        while bits:
            out[n] = 64 * k + trailing_zeros(bits)
            n += 1
            bits &= bits - np.uint64(1)
    return out[:n]


@pytest.mark.slow
@settings(max_examples=100, deadline=None)
@given(st.lists(st.booleans(), min_size=1, max_size=300))
def test_pack_and_set_bits_equal_numpy(bools: list[bool]) -> None:
    words_n = (len(bools) + 63) // 64
    flags = np.zeros(64 * words_n, dtype=np.uint8)
    flags[: len(bools)] = bools
    words = np.zeros(words_n, dtype=np.uint64)
    _pack(flags, words)
    # bit b of word k is flag 64 k + b: numpy's little-endian bit order, eight bytes per word
    expected = np.packbits(flags, bitorder="little").view("<u8")
    assert np.array_equal(words, expected)
    assert np.array_equal(_set_bits(words), np.flatnonzero(flags))
