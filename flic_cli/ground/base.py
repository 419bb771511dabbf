"""The one interface every ground remover implements, and the map from per-point to per-pixel."""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Protocol

import numpy as np
from numba import njit

from flic_cli.range_image import RangeImage


class GroundRemover(Protocol):
    """A ground remover: a component (see :mod:`flic_cli.config.component`) called on a range
    image and the scan's points; returns the (H, W) bool mask of its ground pixels (empty pixels
    are never ground).

    ``points`` are the (N, 3) points of the evaluated point set, point i in pixel
    ``image.point_pixel[i]``; removers that work on the image alone ignore them.
    """

    def __call__(self, image: RangeImage, points: np.ndarray) -> np.ndarray: ...


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
