"""SemanticKITTI's class table: every module that needs a class id, a name or a class group
reads it from here (the names and ids are those of semantic-kitti-api's ``semantic-kitti.yaml``).

Raw ids are the values in the lower 16 bits of a ``.label`` file.
"""

from __future__ import annotations

import numpy as np

#: Raw SemanticKITTI class id -> name.
CLASS_NAMES: dict[int, str] = {
    0: "unlabeled",
    1: "outlier",
    10: "car",
    11: "bicycle",
    13: "bus",
    15: "motorcycle",
    16: "on-rails",
    18: "truck",
    20: "other-vehicle",
    30: "person",
    31: "bicyclist",
    32: "motorcyclist",
    40: "road",
    44: "parking",
    48: "sidewalk",
    49: "other-ground",
    50: "building",
    51: "fence",
    52: "other-structure",
    60: "lane-marking",
    70: "vegetation",
    71: "trunk",
    72: "terrain",
    80: "pole",
    81: "traffic-sign",
    99: "other-object",
    252: "moving-car",
    253: "moving-bicyclist",
    254: "moving-person",
    255: "moving-motorcyclist",
    256: "moving-on-rails",
    257: "moving-bus",
    258: "moving-truck",
    259: "moving-other-vehicle",
}

#: Classes that carry instance ids ("things", static and moving variants).
THING_CLASSES: tuple[int, ...] = (
    10, 11, 13, 15, 16, 18, 20, 30, 31, 32,
    252, 253, 254, 255, 256, 257, 258, 259,
)  # fmt: skip

#: Ground classes, removed by label in the paper's "No Ground" setting.
GROUND_CLASSES: tuple[int, ...] = (40, 44, 48, 49, 60, 72)


def class_name(cls: int) -> str:
    """Name of a raw class id (the id as text when SemanticKITTI has no such class)."""
    return CLASS_NAMES.get(int(cls), str(int(cls)))


def _lut(classes: tuple[int, ...]) -> np.ndarray:
    """Read-only boolean lookup table over all 16-bit semantic ids."""
    lut = np.zeros(1 << 16, dtype=bool)
    lut[list(classes)] = True
    lut.setflags(write=False)
    return lut


#: ``THING_LUT[semantic]`` / ``GROUND_LUT[semantic]``: class-group membership of any 16-bit id.
THING_LUT: np.ndarray = _lut(THING_CLASSES)
GROUND_LUT: np.ndarray = _lut(GROUND_CLASSES)


def ground_mask(labels: np.ndarray) -> np.ndarray:
    """Points whose ground-truth semantic class is a ground class.

    Parameters
    ----------
    labels : (N,) SemanticKITTI labels (``uint32``; semantic class in the lower 16 bits).

    Returns
    -------
    (N,) bool, True where the semantic class is in :data:`GROUND_CLASSES`.
    """
    return GROUND_LUT[np.asarray(labels).astype(np.uint32, copy=False) & 0xFFFF]


def thing_mask(labels: np.ndarray) -> np.ndarray:
    """Points of a thing class that carry an instance id (the points of ground-truth objects).

    Parameters
    ----------
    labels : (N,) SemanticKITTI labels (``uint32``).

    Returns
    -------
    (N,) bool.
    """
    labels = np.asarray(labels).astype(np.uint32, copy=False)
    return THING_LUT[labels & 0xFFFF] & (labels > 0xFFFF)
