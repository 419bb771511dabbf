"""Row flags as 64-bit words, for the numba kernels of the clusterers and the ground removers.

A kernel that computes a flag per pixel of a row in a branch-free (vectorised) loop packs the
flags into words and then visits only the set bits (``trailing_zeros``), instead of testing every
pixel with a branch that the data makes unpredictable.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.cpython.unsafe.numbers import trailing_zeros  # an LLVM cttz intrinsic

__all__ = ["pack", "trailing_zeros"]

#: multiplying 8 bytes of 0/1 by this gathers them in the top byte: byte b -> bit 56 + b
_MAGIC_PACK = np.uint64(0x0102040810204080)


@njit(cache=True, inline="always")
def pack(flags: np.ndarray, words: np.ndarray) -> None:
    """Bit ``b`` of ``words[k]`` = ``flags[64 k + b]`` (flags: uint8 0/1, 64 per word)."""
    f8 = flags.view(np.uint64)
    for k in range(words.size):
        acc = np.uint64(0)
        for b in range(8):
            acc |= ((f8[8 * k + b] * _MAGIC_PACK) >> np.uint64(56)) << np.uint64(8 * b)
        words[k] = acc
