"""The one interface every ground remover implements, the decision per point, and the maps between
points and pixels."""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from typing import Protocol

import numpy as np
from numba import njit

from flic_cli.range_image import RangeImage


class GroundRemover(Protocol):
    """A ground remover: a component (see :mod:`flic_cli.component`) whose one method
    ``extract(image, points) -> Ground`` decides the ground of a scan (:class:`Ground`).

    ``points`` are the (N, 3) points of the evaluated point set, point i in pixel
    ``image.point_pixel[i]``; removers that work on the image alone ignore them. A remover that
    decides per pixel only returns :meth:`Ground.from_mask`; one that decides per point, or holds
    cells out of the clustering, fills the rest of :class:`Ground`.
    """

    def extract(self, image: RangeImage, points: np.ndarray | None) -> Ground: ...


@dataclasses.dataclass(frozen=True)
class Ground:
    """A remover's decision on one scan, as the clusterers take it.

    Attributes
    ----------
    mask : (H, W) bool, the ground pixels (empty pixels are never ground).
    image : the range image the clusterers see: the scan's image, except that the points taken
        as ground whose pixel is not ground have left their pixel (``point_pixel`` -1, not in
        the pixel's point count, :func:`leave_pixels`), so that no clusterer counts or labels
        them.
    decided : (N,) bool, the remover's own decision per point, or None where every point takes
        its pixel's. Where a pixel holds several points (a projected scan), those behind the
        nearest one need not share its decision.
    held : (H, W) bool, the cells held out of the clustering (not ground, never ground
        pixels), or None: none. They are the cells a remover cannot decide on its own (the
        cells under the foot of something standing on the ground, which belong to that thing
        or to the ground): clustered, they would join neighbouring objects to each other along
        the ground; held out, their points take the cluster of the cell standing on them.
    attached : (K, 3) int64, one row per held cell: its flat pixel index, the flat pixel index
        of the cell standing on it whose cluster its points take (-1: none), and its number of
        points in ``image`` (they count towards that cluster's minimum size); None with
        ``held``.
    """

    mask: np.ndarray
    image: RangeImage
    decided: np.ndarray | None = None
    held: np.ndarray | None = None
    attached: np.ndarray | None = None

    def __post_init__(self) -> None:
        if (self.held is None) != (self.attached is None):
            raise ValueError("a Ground has both held cells and their attachments, or neither")

    @classmethod
    def from_mask(cls, image: RangeImage, mask: np.ndarray) -> Ground:
        """The decision of a remover that decides per pixel only: every point takes its
        pixel's decision, the clusterers see ``image`` itself, nothing is held."""
        return cls(np.asarray(mask, dtype=bool), image)

    @functools.cached_property
    def left_out(self) -> np.ndarray:
        """(H, W) bool, the pixels the clusterers leave out: ground and held (computed once per
        scan, however many clusterers share the ground step)."""
        return self.mask if self.held is None else self.mask | self.held

    @property
    def on_ground(self) -> np.ndarray:
        """(N,) bool, the points taken as ground."""
        return point_ground(self.image, self.mask) if self.decided is None else self.decided


def point_ground(image: RangeImage, ground: np.ndarray) -> np.ndarray:
    """Per-point ground decision from a per-pixel mask: every point takes its pixel's.

    Parameters
    ----------
    image : the range image the mask was computed on (``point_pixel`` maps points to pixels).
    ground : (H, W) bool, True = ground pixel.

    Returns
    -------
    (N,) bool, True where the point's pixel is ground; False for points without a pixel.
    """
    flat = np.asarray(ground, dtype=bool).reshape(-1)
    pix = image.point_pixel
    if pix.size and pix.min() >= 0:
        return flat[pix]
    out = np.zeros(pix.size, dtype=bool)
    has = pix >= 0
    out[has] = flat[pix[has]]
    return out


def extract_ground(remover: GroundRemover, image: RangeImage, points: np.ndarray) -> Ground:
    """``remover.extract(image, points)``: its decision on a scan (:class:`Ground`)."""
    return remover.extract(image, points)


def leave_pixels(image: RangeImage, mask: np.ndarray, on_ground: np.ndarray) -> RangeImage:
    """The image the clusterers see given a per-point ground decision: ``image`` with the points
    taken as ground whose pixel is not ``mask`` ground left out of their pixels (``point_pixel``
    -1, not in the pixel's point count); ``image`` itself where there are none.

    Parameters
    ----------
    image : the range image the decision was made on.
    mask : (H, W) bool, the remover's ground pixels.
    on_ground : (N,) bool, the remover's decision per point of ``image``.
    """
    pix, counts, moved = _leave_pixels(
        np.ascontiguousarray(image.point_pixel, dtype=np.int64),
        np.ascontiguousarray(mask, dtype=np.bool_).reshape(-1),
        np.ascontiguousarray(on_ground, dtype=np.bool_),
        np.ascontiguousarray(image.point_counts(), dtype=np.int32).reshape(-1),
    )
    return points_left(image, pix, counts, moved)


def points_left(
    image: RangeImage, point_pixel: np.ndarray, counts: np.ndarray, moved: bool
) -> RangeImage:
    """``image`` with the point-to-pixel map and the (H * W,) point counts of a per-point
    decision that left points out of their pixels; ``image`` itself where none left
    (``moved`` False)."""
    if not moved:
        return image
    return dataclasses.replace(
        image, point_pixel=point_pixel, counts=counts.reshape(image.shape),
        every_point_has_pixel=False,
    )  # fmt: skip


def per_sensor(
    tables: Callable[..., tuple[np.ndarray, ...]],
) -> Callable[..., tuple[np.ndarray, ...]]:
    """Cache a remover's per-row tables once per sensor instead of computing them per frame.

    ``tables(elevation, *args)`` computes arrays from a (H,) float64 elevation table (radians);
    the returned function takes the same arguments (any array-like elevation) and returns the
    cached, read-only arrays, keyed by the table's bytes and ``args``.
    """

    @functools.lru_cache(maxsize=32)
    def cached(elevation: bytes, *args: object) -> tuple[np.ndarray, ...]:
        out = tables(np.frombuffer(elevation, dtype=np.float64), *args)
        for a in out:
            a.setflags(write=False)
        return out

    @functools.wraps(tables)
    def call(elevation: np.ndarray, *args: object) -> tuple[np.ndarray, ...]:
        return cached(np.ascontiguousarray(elevation, dtype=np.float64).tobytes(), *args)

    return call


@njit(cache=True)
def _leave_pixels(
    point_pixel: np.ndarray, mask: np.ndarray, on_ground: np.ndarray, counts: np.ndarray
) -> tuple[np.ndarray, np.ndarray, bool]:
    """``point_pixel`` and ``counts`` without the ground points of pixels that are not ground
    (their pixel -1, not counted), and whether there were any."""
    pix = point_pixel.copy()
    out = counts.copy()
    moved = False
    for i in range(pix.size):
        p = pix[i]
        if p >= 0 and on_ground[i] and not mask[p]:
            pix[i] = -1
            out[p] -= 1
            moved = True
    return pix, out, moved


@njit(cache=True)
def _owners(pix: np.ndarray, rng: np.ndarray, n_pixels: int) -> np.ndarray:
    """Index of the nearest point of every pixel (-1 where no point falls)."""
    owner = np.full(n_pixels, -1, dtype=np.int64)
    for i in range(pix.size):
        p = pix[i]
        if p < 0:
            continue
        o = owner[p]
        if o < 0 or rng[i] < rng[o]:
            owner[p] = i
    return owner


def pixel_owners(image: RangeImage, points: np.ndarray) -> np.ndarray:
    """The point that owns every pixel: the nearest of the points that fall into it.

    This is the point whose range the pixel holds (:func:`flic_cli.projection.project_points`
    keeps the nearest); ties go to the first such point.

    Parameters
    ----------
    image : the range image of ``points`` (``image.point_pixel[i]`` is point i's pixel, -1 = none).
    points : (N, 3+) points, metres.

    Returns
    -------
    (H * W,) int64, the owning point's index per flat pixel, -1 for pixels without a point.
    """
    xyz = np.asarray(points[:, :3], dtype=np.float64)
    rng = np.sqrt(np.einsum("ij,ij->i", xyz, xyz))
    return _owners(np.asarray(image.point_pixel, dtype=np.int64), rng, image.ranges.size)


def pixel_mask(image: RangeImage, points: np.ndarray, point_mask: np.ndarray) -> np.ndarray:
    """Per-pixel mask from a per-point one: a pixel takes the value of the point that owns it.

    Parameters
    ----------
    image : the range image of ``points``.
    points : (N, 3+) points, metres.
    point_mask : (N,) bool, e.g. a point-based remover's ground decision.

    Returns
    -------
    (H, W) bool; False for pixels without a point.
    """
    owner = pixel_owners(image, points)
    point_mask = np.asarray(point_mask, dtype=bool)
    out = np.zeros(owner.size, dtype=bool)
    has = owner >= 0
    out[has] = point_mask[owner[has]]
    return out.reshape(image.ranges.shape)
