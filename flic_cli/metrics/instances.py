"""Instance scores of the FLIC paper (SPEC section 4, paper section 4.B): IoU, P_x, fragments.

Everything here is a plain function over numpy arrays of one frame (or, for :func:`summarize`,
of the pooled objects of many frames); nothing keeps state between calls.

Conventions
-----------
- Ground truth labels are SemanticKITTI ``uint32`` values: ``semantic = label & 0xFFFF``,
  ``instance = label >> 16``.
- Predictions are integer cluster ids per point; ``0`` (and, leniently, any negative value such as
  DBSCAN's ``-1``) means *unclustered*: such a point belongs to no cluster.
- The arrays passed in are the *evaluated point set*: in the "No Ground" setting the caller drops
  the ground points (see :func:`flic_cli.classes.ground_mask`) before calling; cluster sizes are
  counted over exactly the points passed in.

Object matching (:func:`match_objects`)
---------------------------------------
1. A ground-truth object is one full label value whose semantic class is a thing class
   (:data:`flic_cli.classes.THING_CLASSES`) and whose instance id is non-zero, i.e. one
   ``(semantic, instance)`` pair. Objects with fewer than ``min_points`` points are ignored.
2. Each object takes the predicted cluster with the largest overlap (number of shared points).
   Ties between clusters: the smaller cluster (the higher IoU) wins, then the lower cluster id.
3. ``IoU = |A & B| / |A | B| = overlap / (n_points + cluster_size - overlap)``, with the cluster
   size counted over the whole evaluated point set (so background points in the cluster lower the
   IoU, and unclustered object points are simply missed).
4. One cluster, one object: when a cluster is the best match of several objects, only the object
   with the highest IoU keeps it; ties go to the larger overlap, then to the lower instance id
   (then the lower semantic class, i.e. the lower full label value). The others count as not
   found: IoU 0, cluster -1, overlap 0 (they do not fall back to their second-best cluster).
5. Objects overlapping no cluster: IoU 0, cluster -1, overlap 0.

Pooled scores (:func:`summarize`)
---------------------------------
``IoU_mu`` is the mean IoU over all objects of all frames (concatenate the per-object IoUs, do not
average per-frame means). ``P_x`` is the share of objects with ``IoU >= x`` and ``P_mu`` the mean of
``P_x`` over :data:`IOU_THRESHOLDS`. Scores are fractions in ``[0, 1]``.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import NamedTuple

import numpy as np

from flic_cli.classes import thing_mask as _thing_mask

__all__ = [
    "DISTANCE_BANDS",
    "IOU_THRESHOLDS",
    "MIN_FRAGMENT_POINTS",
    "MIN_OBJECT_POINTS",
    "ObjectMatches",
    "distance_band",
    "match_objects",
    "segmentation_stats",
    "summarize",
]

#: IoU thresholds x of P_x: 0.50, 0.55, ..., 0.95 (exact two-decimal values).
IOU_THRESHOLDS: tuple[float, ...] = tuple(
    float(x) for x in np.round(np.linspace(0.50, 0.95, 10), 2)
)

#: Ground-truth objects with fewer points than this are ignored (SPEC section 4).
MIN_OBJECT_POINTS: int = 100

#: A cluster counts as a fragment of an object (or an object as held by a cluster) from this
#: many shared points on; used for over- and under-segmentation.
MIN_FRAGMENT_POINTS: int = 10

#: Range bands of :func:`distance_band`, nearest first.
DISTANCE_BANDS: tuple[str, ...] = ("0-20", "20-40", ">40")

_IOU_SLACK = 1e-12


@dataclass(frozen=True)
class ObjectMatches:
    """Per-object result of :func:`match_objects`; every field is an ``(M,)`` array.

    Objects are ordered by their full label value (instance id, then semantic class).
    ``pandas.DataFrame(matches.as_dict())`` gives one row per object.

    Attributes
    ----------
    label : numpy.ndarray
        ``uint32`` full SemanticKITTI label of the object.
    semantic : numpy.ndarray
        ``int64`` semantic class id.
    instance : numpy.ndarray
        ``int64`` instance id.
    n_points : numpy.ndarray
        ``int64`` number of the object's points in the evaluated point set.
    distance : numpy.ndarray
        ``float64`` Euclidean distance (metres) of the object's centroid from the sensor origin;
        NaN when no points were given.
    cluster : numpy.ndarray
        ``int64`` id of the matched cluster, -1 when not found (no overlapping cluster, or the
        best cluster went to another object).
    overlap : numpy.ndarray
        ``int64`` points shared with the matched cluster (0 when not found).
    iou : numpy.ndarray
        ``float64`` IoU with the matched cluster (0 when not found).
    n_fragments : numpy.ndarray
        ``int64`` number of distinct clusters that hold at least ``min_fragment_points`` of the
        object's points (>= 2 means over-segmented).
    """

    label: np.ndarray
    semantic: np.ndarray
    instance: np.ndarray
    n_points: np.ndarray
    distance: np.ndarray
    cluster: np.ndarray
    overlap: np.ndarray
    iou: np.ndarray
    n_fragments: np.ndarray

    def __len__(self) -> int:
        """Number of objects."""
        return int(self.label.shape[0])

    def as_dict(self) -> dict[str, np.ndarray]:
        """Fields as a column dict, ready for ``pandas.DataFrame``.

        Returns
        -------
        dict of str to numpy.ndarray
            Field name to ``(M,)`` array, in declaration order.
        """
        return {f.name: getattr(self, f.name) for f in fields(self)}


class _Contingency(NamedTuple):
    """Sparse object x cluster contingency table of one frame (internal)."""

    obj_labels: np.ndarray  # (M,) uint32, sorted
    obj_sizes: np.ndarray  # (M,) int64
    cluster_ids: np.ndarray  # (C,) int64, sorted, all > 0
    cluster_sizes: np.ndarray  # (C,) int64, over the whole evaluated point set
    pair_obj: np.ndarray  # (P,) int64 object index, sorted (object-major)
    pair_cluster: np.ndarray  # (P,) int64 cluster index
    pair_overlap: np.ndarray  # (P,) int64 shared points, all > 0
    thing_mask: np.ndarray  # (N,) bool: point of a thing class with an instance id
    thing_obj: np.ndarray  # (T,) int64 object index of each thing point, -1 if ignored


def _as_labels(labels: np.ndarray) -> np.ndarray:
    labels = np.asarray(labels)
    if labels.ndim != 1 or not np.issubdtype(labels.dtype, np.integer):
        raise ValueError(f"labels must be a 1-D integer array, got {labels.dtype} {labels.shape}")
    return labels.astype(np.uint32, copy=False)


def _as_pred(pred: np.ndarray, n: int) -> np.ndarray:
    pred = np.asarray(pred)
    if pred.shape != (n,) or not (
        np.issubdtype(pred.dtype, np.integer) or np.issubdtype(pred.dtype, np.bool_)
    ):
        raise ValueError(
            f"pred must be a 1-D integer array of length {n}, got {pred.dtype} {pred.shape}"
        )
    return pred.astype(np.int64, copy=False)


def _compact(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``np.unique(values, return_inverse=True, return_counts=True)`` for int64 values.

    Uses ``bincount`` when the value range is small compared to the array (the usual case for
    cluster ids), which avoids sorting.
    """
    if values.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    lo = int(values.min())
    span = int(values.max()) - lo + 1
    if span <= 4 * values.size + (1 << 16):
        shifted = values - lo
        counts = np.bincount(shifted, minlength=span)
        present = np.flatnonzero(counts)
        lut = np.empty(span, dtype=np.int64)
        lut[present] = np.arange(present.size, dtype=np.int64)
        return present + lo, lut[shifted], counts[present]
    ids, inverse, counts = np.unique(values, return_inverse=True, return_counts=True)
    return ids.astype(np.int64), inverse.reshape(-1).astype(np.int64), counts.astype(np.int64)


def _contingency(gt_labels: np.ndarray, pred: np.ndarray, min_points: int) -> _Contingency:
    """Objects, clusters and their non-zero overlaps for one frame."""
    gt = _as_labels(gt_labels)
    p = _as_pred(pred, gt.shape[0])
    n = gt.shape[0]

    clustered = p > 0
    cluster_ids, cluster_inv, cluster_sizes = _compact(p[clustered])
    point_cluster = np.full(n, -1, dtype=np.int64)
    point_cluster[clustered] = cluster_inv

    thing_mask = _thing_mask(gt)
    thing_labels = gt[thing_mask]
    all_labels, label_inv, label_counts = np.unique(
        thing_labels, return_inverse=True, return_counts=True
    )
    keep = label_counts >= min_points
    remap = np.where(keep, np.cumsum(keep) - 1, -1)
    thing_obj = remap[label_inv.reshape(-1)]
    obj_labels = all_labels[keep]
    obj_sizes = label_counts[keep].astype(np.int64)

    thing_cluster = point_cluster[thing_mask]
    hit = (thing_obj >= 0) & (thing_cluster >= 0)
    n_clusters = cluster_ids.size
    key = thing_obj[hit] * n_clusters + thing_cluster[hit]
    n_keys = obj_labels.size * n_clusters
    if key.size == 0:
        key_ids = counts = np.zeros(0, dtype=np.int64)
    elif n_keys <= 4 * key.size + (1 << 16):
        dense = np.bincount(key, minlength=n_keys)
        key_ids = np.flatnonzero(dense)
        counts = dense[key_ids]
    else:
        key_ids, counts = np.unique(key, return_counts=True)
    return _Contingency(
        obj_labels=obj_labels,
        obj_sizes=obj_sizes,
        cluster_ids=cluster_ids,
        cluster_sizes=cluster_sizes.astype(np.int64),
        pair_obj=(key_ids // max(n_clusters, 1)).astype(np.int64),
        pair_cluster=(key_ids % max(n_clusters, 1)).astype(np.int64),
        pair_overlap=counts.astype(np.int64),
        thing_mask=thing_mask,
        thing_obj=thing_obj,
    )


def _group_firsts(sorted_groups: np.ndarray) -> np.ndarray:
    """Boolean mask of the first element of each run in a sorted array."""
    first = np.ones(sorted_groups.size, dtype=bool)
    first[1:] = sorted_groups[1:] != sorted_groups[:-1]
    return first


def match_objects(
    gt_labels: np.ndarray,
    pred: np.ndarray,
    points: np.ndarray | None = None,
    min_points: int = MIN_OBJECT_POINTS,
    min_fragment_points: int = MIN_FRAGMENT_POINTS,
) -> ObjectMatches:
    """Match every ground-truth object of one frame to its best predicted cluster.

    The rules (best overlap, IoU, one cluster one object, ties) are in the module docstring.

    Parameters
    ----------
    gt_labels : numpy.ndarray
        ``(N,)`` ``uint32`` SemanticKITTI labels of the evaluated point set.
    pred : numpy.ndarray
        ``(N,)`` integer cluster ids; values ``<= 0`` are unclustered.
    points : numpy.ndarray, optional
        ``(N, 3)`` (or ``(N, >=3)``) point coordinates in the sensor frame, metres; used only for
        :attr:`ObjectMatches.distance`, which is NaN without them.
    min_points : int, default 100
        Objects with fewer points in the evaluated point set are ignored.
    min_fragment_points : int, default 10
        Shared points from which a cluster counts as a fragment of an object.

    Returns
    -------
    ObjectMatches
        One entry per evaluated object, ordered by full label value.

    Raises
    ------
    ValueError
        If the arrays are not 1-D integer arrays of equal length, or ``points`` has the wrong
        shape.
    """
    table = _contingency(gt_labels, pred, min_points)
    n_obj = table.obj_labels.size
    n_pts = table.thing_mask.shape[0]

    p_obj, p_clu, p_ov = table.pair_obj, table.pair_cluster, table.pair_overlap
    p_size = table.cluster_sizes[p_clu]
    p_iou = p_ov / (table.obj_sizes[p_obj] + p_size - p_ov)

    # Best cluster per object: largest overlap, then smaller cluster, then lower cluster id.
    order = np.lexsort((p_clu, p_size, -p_ov, p_obj))
    best = order[_group_firsts(p_obj[order])]
    cand_obj, cand_clu, cand_ov, cand_iou = p_obj[best], p_clu[best], p_ov[best], p_iou[best]

    # One cluster, one object: highest IoU, then larger overlap, then lower label value.
    order = np.lexsort((cand_obj, -cand_ov, -cand_iou, cand_clu))
    winners = order[_group_firsts(cand_clu[order])]

    cluster = np.full(n_obj, -1, dtype=np.int64)
    overlap = np.zeros(n_obj, dtype=np.int64)
    iou = np.zeros(n_obj, dtype=np.float64)
    won = cand_obj[winners]
    cluster[won] = table.cluster_ids[cand_clu[winners]]
    overlap[won] = cand_ov[winners]
    iou[won] = cand_iou[winners]

    n_fragments = np.bincount(p_obj[p_ov >= min_fragment_points], minlength=n_obj)

    distance = np.full(n_obj, np.nan, dtype=np.float64)
    if points is not None:
        pts = np.asarray(points)
        if pts.ndim != 2 or pts.shape[0] != n_pts or pts.shape[1] < 3:
            raise ValueError(f"points must have shape ({n_pts}, 3), got {pts.shape}")
        if n_obj:
            sel = table.thing_obj >= 0
            obj_pts = pts[table.thing_mask][sel, :3].astype(np.float64, copy=False)
            idx = table.thing_obj[sel]
            sums = np.stack(
                [np.bincount(idx, weights=obj_pts[:, k], minlength=n_obj) for k in range(3)],
                axis=1,
            )
            centroid = sums / table.obj_sizes[:, None]
            distance = np.sqrt(np.einsum("ij,ij->i", centroid, centroid))

    return ObjectMatches(
        label=table.obj_labels.astype(np.uint32),
        semantic=(table.obj_labels & 0xFFFF).astype(np.int64),
        instance=(table.obj_labels >> 16).astype(np.int64),
        n_points=table.obj_sizes,
        distance=distance,
        cluster=cluster,
        overlap=overlap,
        iou=iou,
        n_fragments=n_fragments.astype(np.int64),
    )


def segmentation_stats(
    gt_labels: np.ndarray,
    pred: np.ndarray,
    min_points: int = MIN_OBJECT_POINTS,
    min_fragment_points: int = MIN_FRAGMENT_POINTS,
) -> dict[str, int]:
    """Cluster count and over-/under-segmentation counts of one frame.

    Only evaluated objects (thing class, instance id, at least ``min_points`` points) take part.

    - *over-segmented*: objects whose points are spread over at least 2 clusters holding at least
      ``min_fragment_points`` of the object's points each (``n_fragments >= 2``).
    - *under-segmented*: clusters holding at least ``min_fragment_points`` points of each of at
      least 2 objects.

    Parameters
    ----------
    gt_labels : numpy.ndarray
        ``(N,)`` ``uint32`` SemanticKITTI labels of the evaluated point set.
    pred : numpy.ndarray
        ``(N,)`` integer cluster ids; values ``<= 0`` are unclustered.
    min_points : int, default 100
        Objects with fewer points are ignored.
    min_fragment_points : int, default 10
        Shared points from which a cluster and an object count as touching.

    Returns
    -------
    dict of str to int
        ``clusters`` (distinct cluster ids > 0), ``objects`` (evaluated objects),
        ``over_segmented`` (objects), ``under_segmented`` (clusters).
    """
    table = _contingency(gt_labels, pred, min_points)
    touching = table.pair_overlap >= min_fragment_points
    per_obj = np.bincount(table.pair_obj[touching], minlength=table.obj_labels.size)
    per_clu = np.bincount(table.pair_cluster[touching], minlength=table.cluster_ids.size)
    return {
        "clusters": int(table.cluster_ids.size),
        "objects": int(table.obj_labels.size),
        "over_segmented": int(np.count_nonzero(per_obj >= 2)),
        "under_segmented": int(np.count_nonzero(per_clu >= 2)),
    }


def _p_key(x: float) -> str:
    return f"p_{x:.2f}"


def summarize(ious: np.ndarray) -> dict[str, float | int]:
    """Pooled scores over a set of objects (any number of frames, concatenated).

    Parameters
    ----------
    ious : numpy.ndarray
        ``(M,)`` per-object IoUs (0 for objects not found), e.g. the concatenation of
        :attr:`ObjectMatches.iou` over all frames.

    Returns
    -------
    dict
        ``iou_mu`` (mean IoU), ``p_mu`` (mean of the ``P_x``), ``p_0.50`` ... ``p_0.95``
        (share of objects with ``IoU >= x``; a slack of 1e-12 absorbs rounding, so an IoU of
        exactly 0.75 counts for ``p_0.75``), all fractions in ``[0, 1]`` and NaN when there are no
        objects; and ``objects`` (M, an int).
    """
    values = np.asarray(ious, dtype=np.float64).reshape(-1)
    n = values.size
    result: dict[str, float | int] = {}
    if n == 0:
        result["iou_mu"] = float("nan")
        result["p_mu"] = float("nan")
        result.update({_p_key(x): float("nan") for x in IOU_THRESHOLDS})
    else:
        shares = [float(np.count_nonzero(values >= x - _IOU_SLACK)) / n for x in IOU_THRESHOLDS]
        result["iou_mu"] = float(values.mean())
        result["p_mu"] = float(np.mean(shares))
        result.update({_p_key(x): s for x, s in zip(IOU_THRESHOLDS, shares, strict=True)})
    result["objects"] = int(n)
    return result


def distance_band(d: np.ndarray) -> np.ndarray:
    """Range band of each distance.

    Parameters
    ----------
    d : numpy.ndarray
        Distances in metres.

    Returns
    -------
    numpy.ndarray
        String array of the same shape: ``"0-20"`` for ``d < 20``, ``"20-40"`` for
        ``20 <= d < 40``, ``">40"`` for ``d >= 40``, ``"n/a"`` for NaN.
    """
    dist = np.asarray(d, dtype=np.float64)
    return np.select(
        [dist < 20.0, dist < 40.0, dist >= 40.0],
        list(DISTANCE_BANDS),
        default="n/a",
    ).astype("<U5")
