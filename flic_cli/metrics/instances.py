"""Instance scores of the FLIC paper (docs/specification.md, paper 4.B): IoU, P_x, fragments.

Everything here is a plain function over numpy arrays of one frame (or, for :func:`summarize`,
of the pooled objects of many frames); nothing keeps state between calls.

Conventions
-----------
- Ground truth labels are SemanticKITTI ``uint32`` values (:mod:`flic_cli.labels`: semantic
  class in the lower 16 bits, instance id in the upper 16).
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

import numpy as np
from numba import njit

from flic_cli.classes import THING_LUT
from flic_cli.labels import SEMANTIC_MASK, instance, semantic

__all__ = [
    "DISTANCE_BANDS",
    "IOU_THRESHOLDS",
    "MIN_FRAGMENT_POINTS",
    "MIN_OBJECT_POINTS",
    "ObjectMatches",
    "distance_band",
    "match_objects",
    "score_frame",
    "segmentation_stats",
    "summarize",
]

#: IoU thresholds x of P_x: 0.50, 0.55, ..., 0.95 (exact two-decimal values).
IOU_THRESHOLDS: tuple[float, ...] = tuple(
    float(x) for x in np.round(np.linspace(0.50, 0.95, 10), 2)
)

#: Ground-truth objects with fewer points than this are ignored (docs/specification.md).
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
    if pred.dtype in (np.int32, np.int64):
        return pred
    return pred.astype(np.int64)


@njit(cache=True)
def _scan_frame(
    gt: np.ndarray, pred: np.ndarray, thing_lut: np.ndarray, n_ids: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One pass over the points of a frame, one over its thing points.

    Returns
    -------
    sizes : (n_ids,) int64 points of every cluster id (``0 < id < n_ids``; ``sizes[0] = 0``)
    labels : (D,) uint32 the distinct labels of the thing points (objects), in order of appearance
    counts : (D,) int64 their numbers of points
    index : (T,) int64 index of every point of a thing class with an instance id
    slot : (T,) int64 its label's position in ``labels``
    cluster : (T,) int64 its cluster id
    """
    sizes = np.zeros(n_ids, dtype=np.int64)
    n = gt.size
    index = np.empty(n, dtype=np.int64)
    thing_label = np.empty(n, dtype=np.uint32)
    cluster = np.empty(n, dtype=np.int64)
    t = 0
    runs = 0  # runs of equal labels among the thing points: at least the distinct labels
    last = np.uint32(0)  # never a thing label (no instance id)
    for i in range(n):
        p = pred[i]
        if p > 0:
            sizes[p] += 1
        g = gt[i]
        if g > SEMANTIC_MASK and thing_lut[g & SEMANTIC_MASK]:
            runs += g != last
            last = g
            index[t] = i
            thing_label[t] = g
            cluster[t] = p
            t += 1
    # distinct labels: open addressing (linear probing), table at most half full
    size = 64
    while size < 2 * runs:
        size *= 2
    table = np.full(size, -1, dtype=np.int64)  # hash slot -> position in labels
    labels = np.empty(runs, dtype=np.uint32)
    counts = np.zeros(runs, dtype=np.int64)
    slot = np.empty(t, dtype=np.int64)
    n_labels = 0
    last = np.uint32(0)
    s = -1
    for q in range(t):
        g = thing_label[q]
        if g != last:
            k = np.int64((np.uint64(g) * np.uint64(0x9E3779B97F4A7C15)) >> np.uint64(40))
            k &= size - 1
            while table[k] >= 0 and labels[table[k]] != g:
                k = (k + 1) & (size - 1)
            if table[k] < 0:
                table[k] = n_labels
                labels[n_labels] = g
                n_labels += 1
            s = table[k]
            last = g
        counts[s] += 1
        slot[q] = s
    return sizes, labels[:n_labels], counts[:n_labels], index[:t], slot, cluster[:t]


@njit(cache=True)
def _pair_keys(obj: np.ndarray, cluster: np.ndarray, n_ids: int) -> np.ndarray:
    """``object * n_ids + cluster id`` of every thing point of an evaluated object in a cluster."""
    keys = np.empty(obj.size, dtype=np.int64)
    m = 0
    for t in range(obj.size):
        if obj[t] >= 0 and cluster[t] > 0:
            keys[m] = obj[t] * n_ids + cluster[t]
            m += 1
    return keys[:m]


@njit(cache=True)
def _centroid_sums(
    points: np.ndarray, index: np.ndarray, obj: np.ndarray, n_obj: int
) -> np.ndarray:
    """(n_obj, 3) float64 sums of x, y, z over every object's points, added in point order
    (as ``np.bincount(obj, weights=...)`` adds them)."""
    sums = np.zeros((n_obj, 3), dtype=np.float64)
    for t in range(index.size):
        o = obj[t]
        if o >= 0:
            i = index[t]
            for k in range(3):
                sums[o, k] += np.float64(points[i, k])
    return sums


@njit(cache=True)
def _match(
    pair_obj: np.ndarray,
    pair_cluster: np.ndarray,
    pair_overlap: np.ndarray,
    obj_sizes: np.ndarray,
    sizes: np.ndarray,
    min_fragment_points: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """The matching rules of the module docstring over the non-zero overlaps of one frame.

    The pairs are sorted by object, then cluster id. Returns per object the matched cluster id
    (-1), overlap, IoU and fragment count, and the number of under-segmenting clusters.
    """
    n_obj = obj_sizes.size
    cluster = np.full(n_obj, -1, dtype=np.int64)
    overlap = np.zeros(n_obj, dtype=np.int64)
    iou = np.zeros(n_obj, dtype=np.float64)
    n_fragments = np.zeros(n_obj, dtype=np.int64)
    # best cluster per object: largest overlap, then smaller cluster, then lower id (the pairs
    # come in id order, so a full tie keeps the first)
    best_c = np.full(n_obj, -1, dtype=np.int64)
    best_ov = np.zeros(n_obj, dtype=np.int64)
    best_iou = np.zeros(n_obj, dtype=np.float64)
    for q in range(pair_obj.size):
        o, c, ov = pair_obj[q], pair_cluster[q], pair_overlap[q]
        if ov >= min_fragment_points:
            n_fragments[o] += 1
        if best_c[o] < 0 or ov > best_ov[o] or (ov == best_ov[o] and sizes[c] < sizes[best_c[o]]):
            best_c[o] = c
            best_ov[o] = ov
            best_iou[o] = ov / (obj_sizes[o] + sizes[c] - ov)
    # one cluster, one object: highest IoU, then larger overlap, then lower label value
    cand = np.flatnonzero(best_c >= 0)
    order = cand[np.argsort(best_c[cand], kind="mergesort")]
    q = 0
    while q < order.size:
        c = best_c[order[q]]
        win = order[q]
        r = q + 1
        while r < order.size and best_c[order[r]] == c:
            o = order[r]
            if best_iou[o] > best_iou[win] or (
                best_iou[o] == best_iou[win]
                and (best_ov[o] > best_ov[win] or (best_ov[o] == best_ov[win] and o < win))
            ):
                win = o
            r += 1
        cluster[win] = c
        overlap[win] = best_ov[win]
        iou[win] = best_iou[win]
        q = r
    # under-segmentation: clusters holding min_fragment_points of at least two objects
    touching = pair_cluster[pair_overlap >= min_fragment_points]
    touching = np.sort(touching)
    under = 0
    q = 0
    while q < touching.size:
        r = q + 1
        while r < touching.size and touching[r] == touching[q]:
            r += 1
        if r - q >= 2:
            under += 1
        q = r
    return cluster, overlap, iou, n_fragments, under


def score_frame(
    gt_labels: np.ndarray,
    pred: np.ndarray,
    points: np.ndarray | None = None,
    min_points: int = MIN_OBJECT_POINTS,
    min_fragment_points: int = MIN_FRAGMENT_POINTS,
) -> tuple[ObjectMatches, dict[str, int]]:
    """:func:`match_objects` and :func:`segmentation_stats` of one frame in one go.

    Both come from the same object x cluster overlaps, which are counted once; the results are
    exactly those of the two functions (which call this one).

    Parameters
    ----------
    gt_labels, pred, points, min_points, min_fragment_points
        As for :func:`match_objects`.

    Returns
    -------
    (ObjectMatches, dict of str to int)
        The object matches and the segmentation statistics.

    Raises
    ------
    ValueError
        As :func:`match_objects`.
    """
    gt = _as_labels(gt_labels)
    n_pts = gt.shape[0]
    p = _as_pred(pred, n_pts)
    if points is not None:
        pts = np.asarray(points)
        if pts.ndim != 2 or pts.shape[0] != n_pts or pts.shape[1] < 3:
            raise ValueError(f"points must have shape ({n_pts}, 3), got {pts.shape}")

    # cluster ids as dense indices; far-apart ids (rare) are renumbered in id order first
    cluster_ids = None
    top = int(p.max()) if n_pts else 0
    if top >= 4 * n_pts + (1 << 16):
        clustered = p > 0
        cluster_ids, inverse = np.unique(p[clustered], return_inverse=True)
        p = np.zeros(n_pts, dtype=np.int64)
        p[clustered] = inverse.reshape(-1) + 1
        top = cluster_ids.size
    n_ids = max(top, 0) + 1
    sizes, labels, label_counts, thing_index, thing_slot, thing_cluster = _scan_frame(
        gt, p, THING_LUT, n_ids
    )

    # objects: thing labels with at least min_points points, in label order
    order = np.argsort(labels)
    keep = label_counts[order] >= min_points
    obj_labels = labels[order][keep]
    obj_sizes = label_counts[order][keep]
    n_obj = obj_labels.size
    slot_obj = np.empty(labels.size, dtype=np.int64)
    slot_obj[order] = np.where(keep, np.cumsum(keep) - 1, -1)
    thing_obj = slot_obj[thing_slot]

    keys, pair_overlap = np.unique(_pair_keys(thing_obj, thing_cluster, n_ids), return_counts=True)
    pair_obj, pair_cluster = keys // n_ids, keys % n_ids
    cluster, overlap, iou, n_fragments, under = _match(
        pair_obj, pair_cluster, pair_overlap.astype(np.int64), obj_sizes, sizes, min_fragment_points
    )
    if cluster_ids is not None:
        cluster = np.where(cluster > 0, cluster_ids[np.maximum(cluster - 1, 0)], -1)

    distance = np.full(n_obj, np.nan, dtype=np.float64)
    if points is not None and n_obj:
        centroid = _centroid_sums(pts, thing_index, thing_obj, n_obj) / obj_sizes[:, None]
        distance = np.sqrt(np.einsum("ij,ij->i", centroid, centroid))

    matches = ObjectMatches(
        label=obj_labels.astype(np.uint32),
        semantic=semantic(obj_labels).astype(np.int64),
        instance=instance(obj_labels).astype(np.int64),
        n_points=obj_sizes,
        distance=distance,
        cluster=cluster,
        overlap=overlap,
        iou=iou,
        n_fragments=n_fragments,
    )
    stats = {
        "clusters": int(np.count_nonzero(sizes)),
        "objects": int(n_obj),
        "over_segmented": int(np.count_nonzero(n_fragments >= 2)),
        "under_segmented": int(under),
    }
    return matches, stats


def match_objects(
    gt_labels: np.ndarray,
    pred: np.ndarray,
    points: np.ndarray | None = None,
    min_points: int = MIN_OBJECT_POINTS,
    min_fragment_points: int = MIN_FRAGMENT_POINTS,
) -> ObjectMatches:
    """Match every ground-truth object of one frame to its best predicted cluster.

    The rules (best overlap, IoU, one cluster one object, ties) are in the module docstring.
    :func:`score_frame` gives this and :func:`segmentation_stats` in one go.

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
    return score_frame(gt_labels, pred, points, min_points, min_fragment_points)[0]


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
    return score_frame(gt_labels, pred, None, min_points, min_fragment_points)[1]


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
