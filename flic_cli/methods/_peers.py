"""What the field's clusterers (issue 23: Euclidean, HDBSCAN, SLR, CVC, ALPINE) share: which
points they see, how held pixels take their clusters, and a connected-components helper.

Every method here sees the same points as the others: the evaluated point set, without the
points whose pixel the ground step leaves out (``ground.left_out``) or that have no pixel (-1,
outside a spherical projection's field of view). A ground step's held pixels
(:attr:`flic_cli.ground.base.Ground.attached`) link nothing; their points take the cluster of
the pixel standing on them, as for :class:`flic_cli.methods.dbscan.Dbscan`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from flic_cli.methods.base import drop_small, ground_parts
from flic_cli.range_image import RangeImage

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground


def kept_points(image: RangeImage, ground: Ground | None) -> np.ndarray:
    """(N,) bool: the points a 3D method clusters (a pixel, and not left out by ``ground``)."""
    left_out, _ = ground_parts(ground)
    pix = image.point_pixel
    keep = pix >= 0
    if left_out is not None:
        keep &= ~np.asarray(left_out, dtype=bool).reshape(-1)[np.maximum(pix, 0)]
    return keep


def cluster_kept(
    image: RangeImage,
    points: np.ndarray,
    ground: Ground | None,
    raw: Callable[[np.ndarray, np.ndarray], np.ndarray],
    min_size: int,
) -> np.ndarray:
    """Per-point labels of a 3D clusterer on the kept points, held pixels attached.

    Parameters
    ----------
    image, points, ground : as :meth:`flic_cli.methods.base.Method.segment`.
    raw : ``raw(points_kept, kept_index) -> (M,) int`` cluster ids (< 1 = none), any numbering;
        ``kept_index`` are the indices of the kept points in ``points``.
    min_size : smallest cluster kept, points (held points included).

    Returns
    -------
    (N,) int32, 0 = none, 1..K clusters in order of first point.
    """
    keep = kept_points(image, ground)
    idx = np.flatnonzero(keep)
    out = np.zeros(points.shape[0], dtype=np.int64)
    if idx.size:
        out[idx] = raw(points[idx], idx)
    out = np.maximum(out, 0)
    _, attached = ground_parts(ground)
    if attached is not None and len(attached):
        out = attach_held(image, attached, out, keep)
    return drop_small(out, min_size)


def attach_held(
    image: RangeImage, attached: np.ndarray, labels: np.ndarray, keep: np.ndarray
) -> np.ndarray:
    """Give the points of held pixels the cluster of a kept point of the pixel standing on them.

    Parameters
    ----------
    image : the image the points' pixels refer to.
    attached : (K, 3) held pixel, target pixel or -1, points (``Ground.attached``).
    labels : (N,) int per point, 0 = none (only the kept points' labels are read).
    keep : (N,) bool, the points that were clustered.
    """
    pix = image.point_pixel
    cell = np.zeros(image.ranges.size, dtype=np.int64)
    cell[pix[keep]] = labels[keep]
    held, target = attached[:, 0], attached[:, 1]
    cell[held] = np.where(target >= 0, cell[np.maximum(target, 0)], 0)
    is_held = np.zeros(image.ranges.size, dtype=bool)
    is_held[held] = True
    moved = (pix >= 0) & is_held[np.maximum(pix, 0)]
    out = labels.copy()
    out[moved] = cell[pix[moved]]
    return out


def pixel_point_labels(
    image: RangeImage, pixel_labels: np.ndarray, min_size: int, ground: Ground | None = None
) -> np.ndarray:
    """Per-point labels of an image method: held pixels (``ground.attached``) take the label of
    the pixel standing on them, every point its pixel's label, clusters under ``min_size``
    points dropped.

    Parameters
    ----------
    image : the range image the method labelled.
    pixel_labels : (H*W,) int per pixel, 0 = none.
    min_size : smallest cluster kept, points.
    ground : the ground step's decision, or None.
    """
    cell = np.asarray(pixel_labels, dtype=np.int64).reshape(-1).copy()
    _, attached = ground_parts(ground)
    if attached is not None and len(attached):
        held, target = attached[:, 0], attached[:, 1]
        cell[held] = np.where(target >= 0, cell[np.maximum(target, 0)], 0)
    pix = image.point_pixel
    out = np.zeros(pix.size, dtype=np.int64)
    has = pix >= 0
    out[has] = cell[pix[has]]
    return drop_small(out, min_size)


def components(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) component id (0..K-1) of every node of the undirected graph with edges ``a``-``b``
    (:func:`scipy.sparse.csgraph.connected_components`)."""
    graph = coo_matrix((np.ones(a.size, dtype=np.int8), (a, b)), shape=(n, n)).tocsr()
    return connected_components(graph, directed=False)[1]
