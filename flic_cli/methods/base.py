"""The one interface every clusterer implements: range scan in, per-point labels out."""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

from flic_cli.range_image import RangeImage

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground


class Method(Protocol):
    """A clusterer.

    ``segment(image, points, ground)`` returns one int32 label per point of the scan: 0 =
    unclustered or ground, 1..K = clusters. ``ground`` is the ground step's decision
    (:class:`flic_cli.ground.base.Ground`, whose ``image`` is ``image``) or None (nothing
    removed): image methods leave out the pixels of ``ground.left_out``, 3D methods the points
    whose pixel is left out or -1; the points of held cells take the cluster of the cell
    standing on them (``ground.attached``). ``points`` are the scan's (N, 3) points, pixel
    ``image.point_pixel[i]`` for point i.

    What the runs need to know is declared on the class: ``main_param`` names the parameter that
    ``flic sweep-threshold`` varies, ``sweep_range = (from, to, step)`` its default range and
    ``sweep_label`` its axis label (with unit); ``slow = True`` makes ``flic benchmark`` time the
    method on every n-th frame only (``--slow-every``, as DBSCAN). A method that clusters per
    semantic class declares ``needs_semantics`` (ALPINE; it then takes ``semantics=``, the raw
    class of every point, in ``segment``); one that uses the classes in a run with semantics
    (``--semantics``) and clusters without them otherwise declares ``uses_semantics`` (Bridge).
    A method that needs an
    optional package names it in its :data:`flic_cli.registry.METHODS` entry (``requires``,
    ``install``) or defines ``check_installed(self)`` when it depends on a parameter.
    """

    main_param: ClassVar[str]
    sweep_range: ClassVar[tuple[float, float, float]]
    sweep_label: ClassVar[str]
    slow: ClassVar[bool]

    def segment(
        self, image: RangeImage, points: np.ndarray, ground: Ground | None
    ) -> np.ndarray: ...


def ground_parts(ground: Ground | None) -> tuple[np.ndarray | None, np.ndarray | None]:
    """What the kernels read of a ground step: the (H, W) bool pixels left out (ground and held)
    and the (K, 3) held cells' attachments (:attr:`flic_cli.ground.base.Ground.attached`);
    None, None without one."""
    if ground is None:
        return None, None
    return ground.left_out, ground.attached


def point_weights(image: RangeImage) -> np.ndarray | None:
    """Points per pixel of ``image`` for the minimum cluster size, or None for one per node.

    A sensor's own image (:attr:`flic_cli.range_image.RangeImage.one_point_per_pixel`, see
    :func:`flic_cli.range_image.from_sensor_image`) holds exactly one point per valid pixel, so the
    kernels need not read its counts.
    """
    return None if image.one_point_per_pixel else image.point_counts()


def drop_small(labels: np.ndarray, min_size: int, weights: np.ndarray | None = None) -> np.ndarray:
    """Relabel clusters 1..K in order of first appearance, dropping those under ``min_size``.

    Parameters
    ----------
    labels : (N,) int array, values < 1 mean "no cluster".
    min_size : smallest cluster kept, in points (sum of ``weights``).
    weights : (N,) int array, points each entry stands for (e.g. a pixel's
        :meth:`flic_cli.range_image.RangeImage.point_counts`); default 1 each.
    """
    labels = np.asarray(labels)
    out = np.zeros(labels.shape, dtype=np.int32)
    has = labels > 0
    if not has.any():
        return out
    ids, first, inverse, counts = np.unique(
        labels[has], return_index=True, return_inverse=True, return_counts=True
    )
    if weights is not None:
        w = np.asarray(weights).reshape(labels.shape)[has]
        counts = np.bincount(inverse.reshape(-1), weights=w, minlength=ids.size)
    keep = counts >= min_size
    order = np.argsort(first[keep], kind="stable")
    new_id = np.zeros(ids.size, dtype=np.int32)
    new_id[np.flatnonzero(keep)[order]] = np.arange(1, order.size + 1, dtype=np.int32)
    out[has] = new_id[inverse]
    return out
