"""Over- and under-segmentation entropy (OSE, USE) of one frame, as Continuous Clustering's
evaluation computes them (Reich & Wuensche, IV 2024, github.com/UniBwTAS/continuous_clustering,
``src/evaluation/kitti_evaluation.cpp``, ``KittiEvaluation::evaluateClusters``; the metric of
TRAVEL, Oh et al., RA-L 2022).

Per frame, natural logarithm, over every point of the evaluated set, with ``g`` a ground-truth
segment id (0 = none) and ``d`` a predicted cluster id (0 = not clustered):

- OSE = sum over ground-truth segments ``g != 0``, sum over the predicted labels ``d`` met in
  ``g`` (0 included) of ``-(|g and d| / |g|) ln(|g and d| / |g|)``;
- USE = sum over predicted clusters ``d != 0`` that hold at least one point of a segment
  ``g != 0``, sum over the ground-truth labels met in ``d`` (0 included) of
  ``-(|d and g| / |d|) ln(|d and g| / |d|)``.

Both are sums, not means, over the frame's segments (a frame with more objects scores higher);
papers report their mean and standard deviation over frames. The evaluation code reads every
point of the scan; points outside the evaluated set (ground removed by label in flic's
"No Ground" setting) have ``g = 0`` and ``d = 0`` there too, so they change neither sum.

Ground truth: Continuous Clustering splits the points of equal SemanticKITTI label (semantic +
instance) by a Euclidean clustering of 1.0 m with at least 10 points, ground classes and
"unlabeled" set to 0, so every class (buildings and vegetation too) makes segments
(:func:`continuous_clustering_ground_truth`). ``flic evaluate`` takes the protocol's objects
instead (:func:`object_ids`: thing-class instances with at least 100 points in the evaluated
set, as IoU_mu): its OSE/USE measure the objects alone (docs/peers.md).
"""

from __future__ import annotations

import numpy as np

from flic_cli.classes import GROUND_CLASSES, thing_mask
from flic_cli.labels import instance, semantic

__all__ = [
    "continuous_clustering_ground_truth",
    "object_ids",
    "segmentation_entropy",
]


def _entropy_sums(outer: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """Per distinct value of ``outer``: ``sum over inner labels -(f ln f)``, with ``f`` the
    share of the outer segment's points that carry each inner label. Returns (outer ids, sums)
    as a (2, K) float array."""
    if outer.size == 0:
        return np.zeros((2, 0))
    keys = np.stack([outer, inner])
    pairs, counts = np.unique(keys, axis=1, return_counts=True)
    ids, first, n_pairs = np.unique(pairs[0], return_index=True, return_counts=True)
    seg = np.repeat(np.arange(ids.size), n_pairs)
    size = np.bincount(seg, weights=counts)
    f = counts / size[seg]
    return np.stack([ids.astype(np.float64), np.bincount(seg, weights=-f * np.log(f))])


def segmentation_entropy(gt: np.ndarray, pred: np.ndarray) -> tuple[float, float]:
    """(OSE, USE) of one frame (module docstring), natural log.

    Parameters
    ----------
    gt : (N,) int ground-truth segment id per point, 0 = no segment.
    pred : (N,) int predicted cluster id per point, 0 = not clustered.
    """
    g = np.asarray(gt).astype(np.int64).reshape(-1)
    d = np.asarray(pred).astype(np.int64).reshape(-1)
    if g.shape != d.shape:
        raise ValueError(f"gt and pred differ in shape: {g.shape}, {d.shape}")
    in_gt = g != 0
    ose = float(_entropy_sums(g[in_gt], d[in_gt])[1].sum())
    # clusters that hold a ground-truth point; their every point counts (g = 0 as a label)
    touched = np.unique(d[in_gt & (d != 0)])
    in_use = np.isin(d, touched)
    use = float(_entropy_sums(d[in_use], g[in_use])[1].sum())
    return ose, use


def object_ids(labels: np.ndarray, min_points: int = 100) -> np.ndarray:
    """(N,) id (1..K) of every point's evaluated object, 0 for the other points: thing-class
    points with an instance id, grouped by their label, in objects of at least ``min_points``.

    Parameters
    ----------
    labels : (N,) SemanticKITTI labels (uint32) of the evaluated points.
    min_points : smallest object, points (the protocol's 100).
    """
    lab = np.asarray(labels).astype(np.uint32).reshape(-1)
    obj = thing_mask(lab) & (instance(lab) > 0)
    out = np.zeros(lab.size, dtype=np.int64)
    if not obj.any():
        return out
    ids, inverse, counts = np.unique(lab[obj], return_inverse=True, return_counts=True)
    keep = counts >= min_points
    new = np.where(keep, np.cumsum(keep), 0)
    out[obj] = new[inverse.reshape(-1)]
    return out


#: Continuous Clustering's ground-truth clustering (``euclidean_clustering`` namespace of
#: ``kitti_evaluation.hpp``): link distance (m) and smallest segment (points).
CC_DISTANCE_M = 1.0
CC_MIN_POINTS = 10


def continuous_clustering_ground_truth(points: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """(N,) ground-truth segment ids (0 = none) the way Continuous Clustering builds them: the
    points of equal label (semantic + instance) split into the components of a
    :data:`CC_DISTANCE_M` radius graph, components under :data:`CC_MIN_POINTS` points 0, and
    points of the ground classes and of "unlabeled" (class 0) 0.

    PCL's ``ConditionalEuclideanClustering`` there links pairs strictly closer than 1.0 m, as
    :func:`flic_cli.methods.euclidean.radius_components` does.

    Parameters
    ----------
    points : (N, 3) metres.
    labels : (N,) SemanticKITTI labels (uint32).
    """
    from flic_cli.methods.euclidean import radius_components

    lab = np.asarray(labels).astype(np.uint32).reshape(-1)
    sem = semantic(lab)
    out = np.zeros(lab.size, dtype=np.int64)
    skip = np.isin(sem, (0, *GROUND_CLASSES))
    next_id = 1
    values, inverse = np.unique(lab, return_inverse=True)
    inverse = inverse.reshape(-1)
    order = np.argsort(inverse, kind="stable")
    bounds = np.searchsorted(inverse[order], np.arange(values.size + 1))
    for k in range(values.size):
        idx = order[bounds[k] : bounds[k + 1]]
        if skip[idx[0]] or idx.size < CC_MIN_POINTS:
            continue
        comp = radius_components(points[idx], CC_DISTANCE_M)
        sizes = np.bincount(comp)
        big = sizes >= CC_MIN_POINTS
        new = np.where(big, np.cumsum(big) - 1 + next_id, 0)
        out[idx] = new[comp]
        next_id += int(big.sum())
    return out
