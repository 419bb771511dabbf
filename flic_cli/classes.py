"""SemanticKITTI's class table: every module that needs a class id, a name or a class group
reads it from here (the names and ids are those of semantic-kitti-api's ``semantic-kitti.yaml``).

Raw ids are the values in the lower 16 bits of a ``.label`` file. semantic-kitti-api's scripts
(``evaluate_panoptic.py``, ``evaluate_semantics.py``) first map raw ids to 20 *training classes*
(``learning_map``; 0 = unlabeled, ignored), see :data:`LEARNING_MAP` and :func:`learning_class`.
"""

from __future__ import annotations

import numpy as np

from flic_cli.labels import N_IDS, has_instance, semantic

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
    lut = np.zeros(N_IDS, dtype=bool)
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
    return GROUND_LUT[semantic(labels)]


def thing_mask(labels: np.ndarray) -> np.ndarray:
    """Points of a thing class that carry an instance id (the points of ground-truth objects).

    Parameters
    ----------
    labels : (N,) SemanticKITTI labels (``uint32``).

    Returns
    -------
    (N,) bool.
    """
    return THING_LUT[semantic(labels)] & has_instance(labels)


# ---------------------------------------------------------------------------------------------
# semantic-kitti-api's training classes (config/semantic-kitti.yaml: learning_map, labels)
# ---------------------------------------------------------------------------------------------

#: Raw id -> training class id (``learning_map`` of semantic-kitti-api's semantic-kitti.yaml):
#: moving objects join their static class, bus and on-rails become other-vehicle, lane-marking
#: becomes road, and outlier, other-structure and other-object become 0 (unlabeled, ignored).
LEARNING_MAP: dict[int, int] = {
    0: 0, 1: 0, 10: 1, 11: 2, 13: 5, 15: 3, 16: 5, 18: 4, 20: 5, 30: 6, 31: 7, 32: 8,
    40: 9, 44: 10, 48: 11, 49: 12, 50: 13, 51: 14, 52: 0, 60: 9, 70: 15, 71: 16, 72: 17,
    80: 18, 81: 19, 99: 0, 252: 1, 253: 7, 254: 6, 255: 8, 256: 5, 257: 5, 258: 4, 259: 5,
}  # fmt: skip

#: Name of each training class, index = training id (``labels[learning_map_inv[id]]``).
LEARNING_NAMES: tuple[str, ...] = (
    "unlabeled", "car", "bicycle", "motorcycle", "truck", "other-vehicle", "person",
    "bicyclist", "motorcyclist", "road", "parking", "sidewalk", "other-ground", "building",
    "fence", "vegetation", "trunk", "terrain", "pole", "traffic-sign",
)  # fmt: skip

#: Training classes that the evaluation ignores (``learning_ignore``): points whose ground truth
#: is one of them are left out of every score.
LEARNING_IGNORE: tuple[int, ...] = (0,)

#: Thing training classes (``things`` of ``evaluate_panoptic.py``: car, truck, bicycle,
#: motorcycle, other-vehicle, person, bicyclist, motorcyclist) and the stuff ones (road ...
#: traffic-sign). Together they are the 19 classes every panoptic mean is taken over.
LEARNING_THINGS: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7, 8)
LEARNING_STUFF: tuple[int, ...] = (9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19)


def _learning_lut() -> np.ndarray:
    lut = np.zeros(N_IDS, dtype=np.int64)
    lut[list(LEARNING_MAP)] = list(LEARNING_MAP.values())
    lut.setflags(write=False)
    return lut


#: ``LEARNING_LUT[semantic]``: training class of any 16-bit raw id. Ids that SemanticKITTI does
#: not define map to 0 (unlabeled), as semantic-kitti-api's lookup table does for ids up to 358
#: (it fails with an IndexError from 359 on).
LEARNING_LUT: np.ndarray = _learning_lut()


def learning_class(labels: np.ndarray) -> np.ndarray:
    """Training class (semantic-kitti-api's ``learning_map``) of every label.

    Parameters
    ----------
    labels : (N,) SemanticKITTI labels (``uint32``; only the lower 16 bits are read) or raw
        semantic ids.

    Returns
    -------
    (N,) int64 training class ids in ``0..19`` (0 = unlabeled, ignored).
    """
    return LEARNING_LUT[semantic(labels)]
