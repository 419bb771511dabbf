"""Semantics in the predictions: ``flic segment --semantics none | oracle | DIR``.

A panoptic prediction holds, per point, a semantic class (lower 16 bits of the ``.label`` value)
and an instance id (upper 16 bits). flic clusters; the semantics come from elsewhere
(reading and writing them: :mod:`flic_cli.io.semantickitti`):

- ``none`` -- semantic class 0 everywhere (flic's historical output, class-agnostic clusters);
- ``oracle`` -- each point's ground-truth raw class (:func:`oracle_semantics`), the upper bound of
  "semantic network + clustering" used in the literature;
- ``DIR`` -- a semantic network's predictions (:func:`read_semantics`), the standard "semantic
  network + clustering" panoptic baseline.

With semantics, only the points of thing classes are clustered (:func:`cluster_mask`), and
:func:`combine` turns semantics and cluster ids into the labels to write.

Layout of ``DIR`` (decided here)
--------------------------------
``DIR/sequences/<NN>/predictions/<XXXXXX>.label``: the layout that semantic-kitti-api's
``evaluate_semantics.py`` reads, that SemanticKITTI's benchmark asks for, and that ``flic segment``
writes. One ``uint32`` per point of the scan as stored in its ``.bin``; only the lower 16 bits
(the raw SemanticKITTI class, e.g. 10 = car, 40 = road, as written after the inverse
``learning_map``) are read; the upper 16 bits are ignored. Every class must be one that
SemanticKITTI defines (:data:`flic_cli.classes.CLASS_NAMES`).

Unclustered points of thing classes (decided here, from semantic-kitti-api's code)
-----------------------------------------------------------------------------------
semantic-kitti-api's ``PanopticEval`` adds 1 to every label, so instance 0 is *not* "no instance":
all car points with instance 0 would form one car segment, an FP once it reaches 50 points (or
even a TP). It only drops points whose *ground truth* is unlabeled, and it never counts an
unmatched segment under ``min_points`` (50) as FP. Changing the predicted class of the
unclustered points (e.g. to 0, unlabeled) would hide them too, but it changes the semantic mIoU
(every such point becomes a false negative of its class). So :func:`combine` keeps every point's
semantic class (the mIoU is untouched) and gives each unclustered thing point an instance id of
its own: a one-point segment, below any ``min_points >= 2``, never an FP. The ids follow the
largest cluster id (numbered across all classes, in scan order: no two such points share an id,
whatever their classes); should a frame have more such points
than free ids, the ids repeat cyclically, so a segment holds at most
``ceil(points / free ids)`` far-apart points (an error if that would reach 50).

What this still counts (and what an "unclustered" point cannot avoid, since every predicted
point of an evaluated class is in some segment): a one-point segment is a TP exactly when a
ground-truth object has this single point (IoU 1); it never matches a larger object (IoU <= 1/2).
Instance ids of stuff points, and of points whose class maps to unlabeled, are 0 (stuff segments
are then one per raw class, as in the ground truth).
"""

from __future__ import annotations

import numpy as np

from flic_cli.classes import CLASS_NAMES, THING_LUT
from flic_cli.labels import MAX_ID, N_IDS, encode, semantic

__all__ = [
    "MODES",
    "cluster_mask",
    "combine",
    "known_classes",
    "oracle_semantics",
]

#: The named modes of ``--semantics`` (anything else is a folder).
MODES: tuple[str, ...] = ("none", "oracle")

#: Largest id a segment made of unclustered points may reach without ever counting as FP.
_MAX_SINGLETON_SEGMENT = 49

_KNOWN = np.zeros(N_IDS, dtype=bool)
_KNOWN[list(CLASS_NAMES)] = True


def known_classes(semantics: np.ndarray) -> np.ndarray:
    """(N,) bool: True where a raw class id is one SemanticKITTI defines
    (:data:`flic_cli.classes.CLASS_NAMES`)."""
    return _KNOWN[np.asarray(semantics)]


def oracle_semantics(gt_labels: np.ndarray) -> np.ndarray:
    """Each point's ground-truth raw class (``--semantics oracle``).

    Parameters
    ----------
    gt_labels : (N,) SemanticKITTI labels (``uint32``) of every point of the scan.

    Returns
    -------
    (N,) uint16 raw class ids (moving classes stay moving, lane-marking stays lane-marking).
    """
    return semantic(gt_labels).astype(np.uint16)


def cluster_mask(semantics: np.ndarray) -> np.ndarray:
    """The points to cluster: those of a thing class (:data:`flic_cli.classes.THING_CLASSES`).

    Parameters
    ----------
    semantics : (N,) raw class ids (or full labels; only the lower 16 bits are read).

    Returns
    -------
    (N,) bool.
    """
    return THING_LUT[semantic(semantics)]


def combine(semantics: np.ndarray, cluster_ids: np.ndarray) -> np.ndarray:
    """Panoptic labels from semantics and cluster ids (the unclustered-point rule above).

    Parameters
    ----------
    semantics : (N,) raw SemanticKITTI class ids, one per point of the scan.
    cluster_ids : (N,) cluster ids in ``0..65535`` (values <= 0 = unclustered), e.g. from
        clustering the :func:`cluster_mask` points, 0 elsewhere. Ids of points of stuff classes
        are ignored.

    Returns
    -------
    (N,) uint32 labels (:func:`flic_cli.labels.encode`): thing points in a cluster carry its id,
    unclustered thing points one-point segments (ids above the largest cluster id, one per
    point across all classes), every other point instance 0.

    Raises
    ------
    ValueError
        When the arrays differ in length, an id does not fit 16 bits, or a frame has so many
        unclustered thing points that a segment of them would reach 50 points.
    """
    sem = np.asarray(semantics).astype(np.int64)
    ids = np.asarray(cluster_ids).astype(np.int64)
    if sem.ndim != 1 or ids.shape != sem.shape:
        raise ValueError(
            f"semantics and cluster_ids must be 1-D of one length, got {sem.shape}, {ids.shape}"
        )
    if sem.size and (sem.min() < 0 or sem.max() > MAX_ID):
        raise ValueError(f"semantic ids must lie in 0..{MAX_ID}")
    thing = cluster_mask(sem)
    clustered = thing & (ids > 0)
    inst = np.where(clustered, ids, 0)
    loose = np.flatnonzero(thing & ~clustered)
    if loose.size:
        top = int(inst.max(initial=0))
        free = MAX_ID - top
        # one id per point across all classes (in scan order), so that tools scoring the
        # instance id alone (label >> 16) do not merge a car point with a person point
        if free < 1 or -(-loose.size // free) > _MAX_SINGLETON_SEGMENT:
            raise ValueError(
                f"{loose.size} unclustered thing points and {top} clusters do not fit 16-bit "
                "instance ids as segments of under 50 points"
            )
        inst[loose] = top + 1 + np.arange(loose.size) % free
    return encode(sem, inst)
