"""Panoptic quality (PQ = SQ x RQ) exactly as semantic-kitti-api computes it.

The reference is semantic-kitti-api (PRBonn/semantic-kitti-api, read at commit ``a9c749e``):
``evaluate_panoptic.py`` with its class ``PanopticEval`` (``auxiliary/eval_np.py``) and its
``config/semantic-kitti.yaml``. Everything here is a plain function over numpy arrays of one
frame; per-frame results are :class:`PanopticCounts`, which add up over frames (``a + b``,
:meth:`PanopticCounts.total`), and the scores are computed from the pooled counts.

Two scorings
------------
- :func:`panoptic_counts` -- per class, with semantics: ground truth and prediction are both
  SemanticKITTI ``.label`` values (semantic class in the lower 16 bits, instance id in the upper
  16 bits). This is what ``evaluate_panoptic.py`` does with a predictions folder; the means of
  :func:`panoptic_summary` carry the names of its ``scores.txt``.
- :func:`agnostic_panoptic_counts` -- class-agnostic over thing objects: the prediction is plain
  cluster ids (no semantics), every cluster is a candidate "thing" segment, and the ground truth
  segments are this project's ground-truth objects (:mod:`flic_cli.metrics.instances`: points of a
  thing class with a non-zero instance id, one object per full label value). Same conventions
  otherwise (ignore, IoU > 0.5, 50-point minimum), i.e. ``PanopticEval`` run with one thing class.

Conventions of semantic-kitti-api, followed exactly (numbers refer to ``eval_np.py``)
--------------------------------------------------------------------------------------
1. *Classes.* Raw ids are mapped to the 20 training classes with ``learning_map``
   (:data:`flic_cli.classes.LEARNING_MAP`): moving classes join their static class (moving-car ->
   car), bus and on-rails -> other-vehicle, lane-marking -> road, outlier, other-structure and
   other-object -> 0 (unlabeled). Class 0 is ignored (``learning_ignore``); the 19 others are
   evaluated. Raw ids that SemanticKITTI does not define map to 0 (semantic-kitti-api does the
   same up to id 358 and fails from 359 on).
2. *Ignored points.* Every point whose *ground-truth* class is 0 is removed, from the ground truth
   and the prediction alike, before anything is counted. A point *predicted* as class 0 is not
   removed: it belongs to no predicted segment (class 0 is not evaluated) but still counts in the
   area of its ground-truth segment (a miss).
3. *Segments.* Within a class ``c``, a segment is the set of points of class ``c`` that share
   one full 32-bit label value, in the ground truth and in the prediction alike
   (``evaluate_panoptic.py`` passes the whole label as the "instance"). So car instance 5 and
   moving-car instance 5 are two segments of class car; all road points (40) are one segment
   and lane-marking points (60) another segment of class road. The "+1" that
   ``addBatchPanoptic`` adds to every label only keeps instance 0 from vanishing: a point with
   instance id 0 is *not* ignored, it belongs to the segment ``(semantic, instance 0)`` -- all
   thing points with instance 0 of one raw class form one segment. Stuff classes are treated
   exactly like things (no special case).
4. *Matching.* A ground-truth and a predicted segment of the same class match when
   ``IoU = |G & P| / (|G| + |P| - |G & P|) > 0.5`` (strictly; areas counted over the points left
   after step 2, the IoU computed in float64 as ``intersection / union``). Such matches are unique.
5. *TP, FP, FN.* Every match is a TP, whatever its size (a 1-point segment matched by a 1-point
   prediction is a TP). FN: unmatched ground-truth segments of at least ``min_points`` points;
   FP: unmatched predicted segments of at least ``min_points`` points. ``min_points`` is
   :data:`MIN_INSTANCE_POINTS` = 50, ``evaluate_panoptic.py``'s ``--min_inst_points`` default
   (``PanopticEval``'s own default of 30 is not what the script uses).
6. *Pooling.* TP, FP, FN and the IoU sum of the TPs are summed per class over all frames; scores
   come from these sums (a dataset-level PQ, not a mean of per-frame PQs).
7. *Per class.* ``SQ = IoU sum / max(TP, 1e-15)``, ``RQ = TP / max(TP + FP/2 + FN/2, 1e-15)``,
   ``PQ = SQ * RQ`` (= IoU sum / (TP + FP/2 + FN/2)). A class without any segment in ground truth
   and prediction scores 0 (not NaN) *and still counts in every mean* (as in semantic-kitti-api).
8. *Means* (:func:`panoptic_summary`): ``pq_mean``, ``sq_mean``, ``rq_mean`` over the 19 classes
   1..19; ``pq_things`` ... over the thing classes 1..8 (:data:`flic_cli.classes.LEARNING_THINGS`);
   ``pq_stuff`` ... over the stuff classes 9..19; ``pq_dagger`` = mean of PQ over things and
   semantic IoU over stuff; ``iou_mean`` = semantic mIoU over 1..19.
9. *Semantic IoU.* Confusion of predicted against ground-truth class over the points left after
   step 2: ``TP_c`` = points predicted ``c`` with ground truth ``c``, ``FP_c`` = predicted ``c``
   with another ground truth, ``FN_c`` = ground truth ``c`` predicted otherwise (class 0
   included); ``IoU_c = TP_c / max(TP_c + FP_c + FN_c, 1e-15)``. Instance ids play no part.

Class-agnostic scoring (:func:`agnostic_panoptic_counts`) maps every point to one of three
classes and then applies steps 2-7 with the thing class as the only evaluated class: ground truth
class 0 (learning class 0: unlabeled, outlier, other-structure, other-object) is ignored and
removed as in step 2; points of this project's ground-truth objects (thing class *and* instance
id > 0, :func:`flic_cli.classes.thing_mask`) are "thing", segments = full label values;
everything else, including the few thing-class points with instance 0, is "other" (not
evaluated, but it counts in the area of a cluster that holds it). Predicted points with a cluster
id > 0 are "thing", one segment per cluster id; unclustered points (id <= 0) are "other", in no
segment. The scores are the thing class's TP, FP, FN, SQ, RQ, PQ. Differences from the paper's
protocol (:mod:`flic_cli.metrics.instances`): objects count from 50 points (not 100), a match
needs IoU > 0.5, and unlabeled / other-structure / other-object points are left out.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, fields

import numpy as np
from numba import njit

from flic_cli.classes import (
    LEARNING_IGNORE,
    LEARNING_LUT,
    LEARNING_NAMES,
    LEARNING_STUFF,
    LEARNING_THINGS,
    THING_LUT,
    learning_class,
    thing_mask,
)
from flic_cli.labels import SEMANTIC_MASK

__all__ = [
    "EPS",
    "IOU_MATCH",
    "MIN_INSTANCE_POINTS",
    "PanopticCounts",
    "agnostic_panoptic_counts",
    "agnostic_scores",
    "class_scores",
    "panoptic_counts",
    "panoptic_summary",
    "pq_sq_rq",
    "segment_counts",
]

#: Segments with fewer points are never counted as FP or FN (``--min_inst_points`` default).
MIN_INSTANCE_POINTS: int = 50

#: A ground-truth and a predicted segment match when their IoU is strictly above this.
IOU_MATCH: float = 0.5

#: semantic-kitti-api's guard against division by zero (``PanopticEval.eps``).
EPS: float = 1e-15

_CLASS_SHIFT = 33  # segment keys: class << 33 | (label + 1), label + 1 < 2**33


@dataclass(frozen=True)
class PanopticCounts:
    """Per-class counts of one frame or of many (they add up); every field is a ``(C,)`` array.

    Index = class: for :func:`panoptic_counts` the training class id 0..19 (names in
    :data:`flic_cli.classes.LEARNING_NAMES`; index 0, the ignored class, stays 0 except
    ``sem_fp``), for :func:`agnostic_panoptic_counts` a single entry (the thing class).

    Attributes
    ----------
    tp, fp, fn : numpy.ndarray
        ``int64`` matched segment pairs, unmatched predicted segments (>= min points),
        unmatched ground-truth segments (>= min points).
    iou_sum : numpy.ndarray
        ``float64`` sum of the IoUs of the TPs.
    sem_tp, sem_fp, sem_fn : numpy.ndarray
        ``int64`` point counts of the semantic confusion (convention 9 of the module docstring).
    """

    tp: np.ndarray
    fp: np.ndarray
    fn: np.ndarray
    iou_sum: np.ndarray
    sem_tp: np.ndarray
    sem_fp: np.ndarray
    sem_fn: np.ndarray

    @classmethod
    def zeros(cls, n_classes: int) -> PanopticCounts:
        """All-zero counts for ``n_classes`` classes."""
        z = np.zeros(n_classes, dtype=np.int64)
        return cls(z, z, z, np.zeros(n_classes, dtype=np.float64), z, z, z)

    def __add__(self, other: PanopticCounts) -> PanopticCounts:
        """Element-wise sum (counts of two frames pooled)."""
        if not isinstance(other, PanopticCounts):
            return NotImplemented
        return PanopticCounts(
            *(getattr(self, f.name) + getattr(other, f.name) for f in fields(self))
        )

    @classmethod
    def total(cls, counts: Iterable[PanopticCounts], n_classes: int) -> PanopticCounts:
        """Sum of per-frame counts (all-zero counts of ``n_classes`` classes when empty)."""
        out = cls.zeros(n_classes)
        for c in counts:
            out = out + c
        return out

    def __len__(self) -> int:
        """Number of classes."""
        return int(self.tp.shape[0])

    def as_dict(self) -> dict[str, np.ndarray]:
        """Fields as a column dict (one row per class), ready for ``pandas.DataFrame``."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


def _check(name: str, a: np.ndarray, n: int | None = None) -> np.ndarray:
    a = np.asarray(a)
    if a.ndim != 1 or not np.issubdtype(a.dtype, np.integer):
        raise ValueError(f"{name} must be a 1-D integer array, got {a.dtype} {a.shape}")
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{name} has {a.shape[0]} values, expected {n}")
    return a


def segment_counts(
    pred_class: np.ndarray,
    pred_segment: np.ndarray,
    gt_class: np.ndarray,
    gt_segment: np.ndarray,
    n_classes: int,
    ignore: Iterable[int] = LEARNING_IGNORE,
    min_points: int = MIN_INSTANCE_POINTS,
) -> PanopticCounts:
    """``PanopticEval.addBatch`` for one frame, on class ids and segment ids (steps 2-5, 9).

    Parameters
    ----------
    pred_class, gt_class : numpy.ndarray
        ``(N,)`` class ids in ``0..n_classes-1`` of every point.
    pred_segment, gt_segment : numpy.ndarray
        ``(N,)`` non-negative segment ids, below ``2**33``: points of one class with the same id
        form one segment (semantic-kitti-api passes ``label + 1``, the full label shifted by one).
    n_classes : int
        Number of classes.
    ignore : iterable of int, default (0,)
        Classes not evaluated; points whose ground truth is one of them are removed first.
    min_points : int, default 50
        Unmatched segments with fewer points are neither FP nor FN.

    Returns
    -------
    PanopticCounts
        ``(n_classes,)`` counts; the ignored classes have zero TP, FP, FN.

    Raises
    ------
    ValueError
        When the arrays are not 1-D integer arrays of one length, or a class id is out of range.
    """
    pc = _check("pred_class", pred_class).astype(np.int64, copy=False)
    n = pc.shape[0]
    gc = _check("gt_class", gt_class, n).astype(np.int64, copy=False)
    ps = _check("pred_segment", pred_segment, n).astype(np.int64, copy=False)
    gs = _check("gt_segment", gt_segment, n).astype(np.int64, copy=False)
    for name, c in (("pred_class", pc), ("gt_class", gc)):
        if c.size and (c.min() < 0 or c.max() >= n_classes):
            raise ValueError(f"{name} values must lie in 0..{n_classes - 1}")
    ignored = np.zeros(n_classes, dtype=bool)
    ignored[list(ignore)] = True

    keep = ~ignored[gc]  # step 2: ground truth in an ignored class -> point removed
    pc, gc, ps, gs = pc[keep], gc[keep], ps[keep], gs[keep]

    # Semantic confusion (step 9).
    sem_tp = np.bincount(pc[pc == gc], minlength=n_classes)
    sem_fp = np.bincount(pc, minlength=n_classes) - sem_tp
    sem_fn = np.bincount(gc, minlength=n_classes) - sem_tp

    # Segments (step 3): key = class << 33 | segment id, only for evaluated classes.
    p_in, g_in = ~ignored[pc], ~ignored[gc]
    p_keys, p_inv, p_area = np.unique(
        (pc[p_in] << _CLASS_SHIFT) | ps[p_in], return_inverse=True, return_counts=True
    )
    g_keys, g_inv, g_area = np.unique(
        (gc[g_in] << _CLASS_SHIFT) | gs[g_in], return_inverse=True, return_counts=True
    )
    p_idx = np.full(pc.shape[0], -1, dtype=np.int64)
    p_idx[p_in] = p_inv.reshape(-1)
    g_idx = np.full(gc.shape[0], -1, dtype=np.int64)
    g_idx[g_in] = g_inv.reshape(-1)

    # Intersections (step 4): points whose predicted and true class agree.
    both = p_in & (pc == gc)
    n_g = max(g_keys.size, 1)
    pairs, inter = np.unique(p_idx[both] * n_g + g_idx[both], return_counts=True)
    pi, gi = pairs // n_g, pairs % n_g
    union = p_area[pi] + g_area[gi] - inter
    iou = inter.astype(np.float64) / union.astype(np.float64)
    match = iou > IOU_MATCH

    # TP, FP, FN (step 5).
    cls_pair = p_keys[pi[match]] >> _CLASS_SHIFT
    tp = np.bincount(cls_pair, minlength=n_classes)
    iou_sum = np.bincount(cls_pair, weights=iou[match], minlength=n_classes)
    p_matched = np.zeros(p_keys.size, dtype=bool)
    p_matched[pi[match]] = True
    g_matched = np.zeros(g_keys.size, dtype=bool)
    g_matched[gi[match]] = True
    fp = np.bincount(
        p_keys[~p_matched & (p_area >= min_points)] >> _CLASS_SHIFT, minlength=n_classes
    )
    fn = np.bincount(
        g_keys[~g_matched & (g_area >= min_points)] >> _CLASS_SHIFT, minlength=n_classes
    )
    return PanopticCounts(
        tp.astype(np.int64),
        fp.astype(np.int64),
        fn.astype(np.int64),
        iou_sum.astype(np.float64),
        sem_tp.astype(np.int64),
        sem_fp.astype(np.int64),
        sem_fn.astype(np.int64),
    )


def panoptic_counts(
    gt_labels: np.ndarray, pred_labels: np.ndarray, min_points: int = MIN_INSTANCE_POINTS
) -> PanopticCounts:
    """Per-class panoptic counts of one frame, semantic-kitti-api's way.

    Parameters
    ----------
    gt_labels : numpy.ndarray
        ``(N,)`` ground-truth SemanticKITTI labels (``uint32``: semantic class in the lower 16
        bits, instance id in the upper 16 bits), one per point of the scan.
    pred_labels : numpy.ndarray
        ``(N,)`` predicted labels in the same encoding (as in a predictions ``.label`` file).
    min_points : int, default 50
        ``--min_inst_points`` of ``evaluate_panoptic.py``.

    Returns
    -------
    PanopticCounts
        20 entries, index = training class id (0 = unlabeled, ignored).
    """
    gt = _check("gt_labels", gt_labels).astype(np.uint32, copy=False)
    pred = _check("pred_labels", pred_labels, gt.shape[0]).astype(np.uint32, copy=False)
    return segment_counts(
        learning_class(pred),
        pred.astype(np.int64) + 1,
        learning_class(gt),
        gt.astype(np.int64) + 1,
        len(LEARNING_NAMES),
        LEARNING_IGNORE,
        min_points,
    )


def agnostic_panoptic_counts(
    gt_labels: np.ndarray, pred: np.ndarray, min_points: int = MIN_INSTANCE_POINTS
) -> PanopticCounts:
    """Class-agnostic panoptic counts of one frame over thing objects (see the module docstring).

    Parameters
    ----------
    gt_labels : numpy.ndarray
        ``(N,)`` ground-truth SemanticKITTI labels (``uint32``) of the evaluated point set.
    pred : numpy.ndarray
        ``(N,)`` cluster ids; values ``<= 0`` are unclustered (in no segment).
    min_points : int, default 50
        Unmatched objects or clusters with fewer points (after removing the ignored points) are
        neither FN nor FP.

    Returns
    -------
    PanopticCounts
        One entry: the thing class. ``sem_*`` count thing points (ground-truth object points
        against clustered points).
    """
    gt = _check("gt_labels", gt_labels).astype(np.uint32, copy=False)
    p = _check("pred", pred, gt.shape[0]).astype(np.int64, copy=False)
    # :func:`segment_counts` with classes 1 (thing object / clustered), 2 (other) and 0 (ignored)
    # gives the same counts (see :func:`agnostic_panoptic_counts_reference`); done here directly,
    # on the few thing points, it is several times faster (it runs for every method and frame).
    p_area, t_label, t_cluster, n_clustered = _agnostic_pass(
        gt, p, LEARNING_LUT != 0, THING_LUT, int(p.max(initial=0)) + 1
    )
    labels, g_inv, g_area = np.unique(t_label, return_inverse=True, return_counts=True)
    hit = t_cluster > 0
    n_ids = p_area.size
    keys, inter = np.unique(g_inv.reshape(-1)[hit] * n_ids + t_cluster[hit], return_counts=True)
    gi, pi = keys // n_ids, keys % n_ids
    iou = inter / (g_area[gi] + p_area[pi] - inter).astype(np.float64)
    match = iou > IOU_MATCH
    g_matched = np.zeros(labels.size, dtype=bool)
    g_matched[gi[match]] = True
    p_matched = np.zeros(n_ids, dtype=bool)
    p_matched[pi[match]] = True
    sem_tp = int(np.count_nonzero(hit))
    counts = [
        np.count_nonzero(match),
        np.count_nonzero(~p_matched & (p_area >= max(min_points, 1))),  # id 0: no segment
        np.count_nonzero(~g_matched & (g_area >= min_points)),
        np.sum(iou[match]),
        sem_tp,
        n_clustered - sem_tp,
        t_label.size - sem_tp,
    ]
    return PanopticCounts(
        *(np.array([v], dtype=np.float64 if k == 3 else np.int64) for k, v in enumerate(counts))
    )


@njit(cache=True)
def _agnostic_pass(
    gt: np.ndarray, p: np.ndarray, evaluated: np.ndarray, thing: np.ndarray, n_ids: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """One pass over the points: predicted segment areas (clustered points whose ground truth is
    evaluated, by cluster id), the labels and cluster ids of the thing-object points, and the
    number of clustered evaluated points."""
    area = np.zeros(n_ids, dtype=np.int64)
    n_thing = 0
    for i in range(gt.size):
        if thing[gt[i] & SEMANTIC_MASK] and gt[i] > SEMANTIC_MASK:
            n_thing += 1
    t_label = np.empty(n_thing, dtype=np.uint32)
    t_cluster = np.empty(n_thing, dtype=np.int64)
    k = 0
    n_clustered = 0
    for i in range(gt.size):
        g = gt[i]
        c = p[i]
        if c > 0 and evaluated[g & SEMANTIC_MASK]:
            area[c] += 1
            n_clustered += 1
        if thing[g & SEMANTIC_MASK] and g > SEMANTIC_MASK:
            t_label[k] = g
            t_cluster[k] = c
            k += 1
    return area, t_label, t_cluster, n_clustered


def agnostic_panoptic_counts_reference(
    gt_labels: np.ndarray, pred: np.ndarray, min_points: int = MIN_INSTANCE_POINTS
) -> PanopticCounts:
    """:func:`agnostic_panoptic_counts` through the general :func:`segment_counts` (the
    definition; slower): classes 1 = ground-truth thing object / clustered point, 2 = any other
    point, 0 = ignored (learning class 0)."""
    gt = _check("gt_labels", gt_labels).astype(np.uint32, copy=False)
    p = _check("pred", pred, gt.shape[0]).astype(np.int64, copy=False)
    gt_class = np.where(thing_mask(gt), 1, 2)
    gt_class[learning_class(gt) == 0] = 0
    pred_class = np.where(p > 0, 1, 2)
    counts = segment_counts(
        pred_class, np.maximum(p, 0) + 1, gt_class, gt.astype(np.int64) + 1, 3, (0,), min_points
    )
    return PanopticCounts(*(v[1:2] for v in counts.as_dict().values()))


def pq_sq_rq(
    tp: np.ndarray, fp: np.ndarray, fn: np.ndarray, iou_sum: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """PQ, SQ, RQ per class from pooled counts (``PanopticEval.getPQ``; convention 7).

    Parameters
    ----------
    tp, fp, fn, iou_sum : numpy.ndarray
        Per-class pooled counts and IoU sums (any equal shapes, scalars too).

    Returns
    -------
    (pq, sq, rq) : tuple of numpy.ndarray
        Fractions in ``[0, 1]``; 0 (not NaN) where a class has no segment at all.
    """
    tp = np.asarray(tp, dtype=np.float64)
    sq = np.asarray(iou_sum, dtype=np.float64) / np.maximum(tp, EPS)
    rq = tp / np.maximum(
        tp + 0.5 * np.asarray(fp, dtype=np.float64) + 0.5 * np.asarray(fn, dtype=np.float64),
        EPS,
    )
    return sq * rq, sq, rq


def class_scores(counts: PanopticCounts) -> dict[str, np.ndarray]:
    """Per-class scores of pooled counts: PQ, SQ, RQ and semantic IoU, one value per class.

    Returns
    -------
    dict of str to numpy.ndarray
        ``pq``, ``sq``, ``rq``, ``iou`` (``float64`` fractions) and ``tp``, ``fp``, ``fn``
        (``int64``), each ``(C,)``.
    """
    pq, sq, rq = pq_sq_rq(counts.tp, counts.fp, counts.fn, counts.iou_sum)
    union = (counts.sem_tp + counts.sem_fp + counts.sem_fn).astype(np.float64)
    iou = counts.sem_tp.astype(np.float64) / np.maximum(union, EPS)
    return {
        "pq": pq,
        "sq": sq,
        "rq": rq,
        "iou": iou,
        "tp": counts.tp,
        "fp": counts.fp,
        "fn": counts.fn,
    }


def panoptic_summary(counts: PanopticCounts) -> dict[str, float]:
    """The means of ``evaluate_panoptic.py`` (its ``scores.txt``) from pooled 20-class counts.

    Parameters
    ----------
    counts : PanopticCounts
        Pooled :func:`panoptic_counts` (20 classes).

    Returns
    -------
    dict of str to float
        ``pq_mean``, ``pq_dagger``, ``sq_mean``, ``rq_mean``, ``iou_mean``, ``pq_stuff``,
        ``rq_stuff``, ``sq_stuff``, ``pq_things``, ``rq_things``, ``sq_things`` (convention 8),
        fractions in ``[0, 1]``.
    """
    if len(counts) != len(LEARNING_NAMES):
        raise ValueError(f"expected counts of {len(LEARNING_NAMES)} classes, got {len(counts)}")
    s = class_scores(counts)
    things, stuff = list(LEARNING_THINGS), list(LEARNING_STUFF)
    evaluated = things + stuff
    out = {
        "pq_mean": s["pq"][evaluated].mean(),
        "pq_dagger": np.concatenate([s["pq"][things], s["iou"][stuff]]).mean(),
        "sq_mean": s["sq"][evaluated].mean(),
        "rq_mean": s["rq"][evaluated].mean(),
        "iou_mean": s["iou"][evaluated].mean(),
        "pq_stuff": s["pq"][stuff].mean(),
        "rq_stuff": s["rq"][stuff].mean(),
        "sq_stuff": s["sq"][stuff].mean(),
        "pq_things": s["pq"][things].mean(),
        "rq_things": s["rq"][things].mean(),
        "sq_things": s["sq"][things].mean(),
    }
    return {k: float(v) for k, v in out.items()}


def agnostic_scores(counts: PanopticCounts) -> dict[str, float | int]:
    """PQ, SQ, RQ of pooled class-agnostic counts (:func:`agnostic_panoptic_counts`).

    Returns
    -------
    dict
        ``pq``, ``sq``, ``rq`` (fractions in ``[0, 1]``, 0 when there is no segment at all) and
        ``tp``, ``fp``, ``fn``, ``iou_sum``.
    """
    if len(counts) != 1:
        raise ValueError(f"expected class-agnostic counts (1 class), got {len(counts)} classes")
    pq, sq, rq = pq_sq_rq(counts.tp[0], counts.fp[0], counts.fn[0], counts.iou_sum[0])
    return {
        "pq": float(pq),
        "sq": float(sq),
        "rq": float(rq),
        "tp": int(counts.tp[0]),
        "fp": int(counts.fp[0]),
        "fn": int(counts.fn[0]),
        "iou_sum": float(counts.iou_sum[0]),
    }
