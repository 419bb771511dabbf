"""The SemanticKITTI label encoding, in one place.

A label is one ``uint32`` per point: the semantic class in the lower 16 bits and the instance id
in the upper 16 bits (0 = no instance), ``label = instance << 16 | semantic``. Ground truth
(``.label`` files) and flic's predictions use it alike. Nothing else in flic spells these bits:
numpy code calls :func:`semantic`, :func:`instance`, :func:`has_instance` and :func:`encode`;
numba kernels use :data:`SEMANTIC_MASK` and :data:`INSTANCE_SHIFT` (module constants, which numba
compiles in as literals).

Example
-------
>>> import numpy as np
>>> lab = encode(np.array([10, 40]), np.array([3, 0]))
>>> lab.tolist(), semantic(lab).tolist(), instance(lab).tolist()
([196618, 40], [10, 40], [3, 0])
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "INSTANCE_SHIFT",
    "MAX_ID",
    "N_IDS",
    "SEMANTIC_MASK",
    "encode",
    "has_instance",
    "instance",
    "semantic",
]

#: Bits of the semantic class (the lower 16).
SEMANTIC_MASK: int = 0xFFFF
#: Shift of the instance id (the upper 16 bits).
INSTANCE_SHIFT: int = 16
#: Largest semantic class or instance id that fits (65535).
MAX_ID: int = SEMANTIC_MASK
#: Number of distinct semantic (or instance) ids: the size of a lookup table over classes.
N_IDS: int = SEMANTIC_MASK + 1


def _as_labels(labels: np.ndarray) -> np.ndarray:
    return np.asarray(labels).astype(np.uint32, copy=False)


def semantic(labels: np.ndarray) -> np.ndarray:
    """Semantic class ids (lower 16 bits) of encoded labels.

    Parameters
    ----------
    labels : (N,) encoded labels (any integer dtype; read as ``uint32``).

    Returns
    -------
    (N,) uint32 class ids in ``0..65535``.
    """
    return _as_labels(labels) & SEMANTIC_MASK


def instance(labels: np.ndarray) -> np.ndarray:
    """Instance ids (upper 16 bits) of encoded labels; 0 = none.

    Parameters
    ----------
    labels : (N,) encoded labels (any integer dtype; read as ``uint32``).

    Returns
    -------
    (N,) uint32 instance ids in ``0..65535``.
    """
    return _as_labels(labels) >> INSTANCE_SHIFT


def has_instance(labels: np.ndarray) -> np.ndarray:
    """(N,) bool: True where a label carries an instance id (``instance(labels) > 0``)."""
    return _as_labels(labels) > SEMANTIC_MASK


def encode(semantic_ids: np.ndarray, instance_ids: np.ndarray) -> np.ndarray:
    """Encode semantic class and instance ids as labels.

    Parameters
    ----------
    semantic_ids, instance_ids : (N,) integer arrays (or scalars) with values in ``0..65535``.

    Returns
    -------
    (N,) uint32 array ``instance << 16 | semantic``.

    Raises
    ------
    ValueError
        When an id lies outside ``0..65535``.
    """
    sem = np.asarray(semantic_ids, dtype=np.int64)
    ins = np.asarray(instance_ids, dtype=np.int64)
    for name, ids in (("semantic", sem), ("instance", ins)):
        if ids.size and (ids.min() < 0 or ids.max() > MAX_ID):
            raise ValueError(
                f"{name} ids must lie in 0..{MAX_ID} to fit 16 bits, got {ids.min()}..{ids.max()}"
            )
    return ((ins << INSTANCE_SHIFT) | sem).astype(np.uint32)
