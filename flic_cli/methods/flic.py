"""FLIC: Euclidean clustering on the range image with Map Connections (paper section III-B)."""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, Annotated, ClassVar, Literal

import numpy as np
from pydantic import Field, NonNegativeInt, field_validator
from pydantic.dataclasses import dataclass

from flic_cli.component import STRICT
from flic_cli.methods.base import ground_parts
from flic_cli.methods.connections import DISTANCE, offset_input, run_kernel, segment_image
from flic_cli.methods.criteria import ray_angle
from flic_cli.range_image import RangeImage

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground

MC_MODES = ("map", "neighbour")


def connection_sets(
    maps: tuple[tuple[int, int], ...] | list, mc_mode: str = "map"
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The connection sets of the kernel: direct neighbours first, then one per Map Connection.

    Parameters
    ----------
    maps : steps ``(rows, cols)`` or ``(rows, cols, row_offset, col_offset)`` of each MC.
    mc_mode : ``"map"``: an MC is the sub-image of every step-th row and column (from the offset),
        clustered with the same distance test at the angle of that step and merged into the direct
        clusters. ``"neighbour"``: every measurement is connected to its step-th neighbour below
        and to the right (the union of the map reading over all offsets).

    Returns
    -------
    steps (M, 2), offsets (M, 2), lattice (M,) arrays for
    :func:`flic_cli.methods.connections.components`.
    """
    if mc_mode not in MC_MODES:
        raise ValueError(f"mc_mode must be one of {MC_MODES}, got {mc_mode!r}")
    steps = [(1, 1)]
    offsets = [(0, 0)]
    for m in maps:
        m = check_map(m)
        steps.append(m[:2])
        offsets.append(m[2:] if len(m) == 4 else (0, 0))
    lattice = [True] + [mc_mode == "map"] * len(maps)
    return (
        np.array(steps, dtype=np.int64),
        np.array(offsets, dtype=np.int64),
        np.array(lattice, dtype=np.bool_),
    )


def check_map(m: tuple | list) -> tuple[int, ...]:
    """One Map Connection as ints: ``(row_step, col_step[, row_offset, col_offset])``, steps
    >= 1, offsets >= 0; ValueError otherwise."""
    m = tuple(int(v) for v in m)
    if len(m) not in (2, 4) or min(m[:2]) < 1 or min(m[2:], default=0) < 0:
        raise ValueError(
            "a map is [row_step, col_step] or [row_step, col_step, row_offset, col_offset] "
            f"with steps >= 1 and offsets >= 0, got {list(m)}"
        )
    return m


def maps_key(maps: tuple | list) -> tuple[tuple[int, ...], ...]:
    """``maps`` as a hashable tuple of int tuples."""
    return tuple(tuple(int(v) for v in m) for m in maps)


@lru_cache(maxsize=256)
def cached_sets(
    maps: tuple[tuple[int, ...], ...], mc_mode: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`connection_sets`, built once per maps and reading (read-only arrays)."""
    sets = connection_sets(maps, mc_mode)
    for a in sets:
        a.flags.writeable = False
    return sets


def _linked(d1: np.ndarray, d2: np.ndarray, cos_a: np.ndarray, t2: float) -> np.ndarray:
    return d1 * d1 + d2 * d2 - 2.0 * cos_a * d1 * d2 < t2


def _vertical_cos(el: np.ndarray, offset: np.ndarray, rows: np.ndarray, step: int) -> np.ndarray:
    """(len(rows) - step, 1) cos of the angle between the rays of ``rows[i]`` and
    ``rows[i + step]`` in one column (:func:`flic_cli.methods.criteria.ray_angle`)."""
    a, b = rows[:-step], rows[step:]
    angles = [ray_angle(el[i], el[j], offset[i], offset[j]) for i, j in zip(a, b, strict=True)]
    return np.cos(np.array(angles, dtype=np.float64).reshape(-1))[:, None]


def _row_cos(elevation: np.ndarray, cols: float, width: int) -> np.ndarray:
    """(H, 1) cos of the angle between two rays of one row ``cols`` columns apart."""
    ce2 = np.cos(elevation) ** 2
    return (ce2 * np.cos(cols * 2.0 * np.pi / width) + (1.0 - ce2))[:, None]


@dataclass(frozen=True, config=STRICT)
class Flic:
    """FLIC as a :class:`flic_cli.methods.base.Method` (see :func:`flic_labels`).

    Attributes
    ----------
    threshold_m : distance threshold t, metres.
    min_size : smallest cluster kept, points of the evaluated set (a pixel counts its points).
    maps : Map Connections, ``[row_step, col_step]`` or ``[row_step, col_step, row_offset,
        col_offset]`` each (see :func:`connection_sets`).
    mc_mode : ``"map"`` (an MC is the sub-image of every step-th row and column) or
        ``"neighbour"`` (every measurement to its step-th neighbour).
    backend : ``"numba"`` (the union-find kernel) or ``"scipy"`` (:func:`flic_labels_scipy`,
        the paper's way: same labels, slower).
    """

    threshold_m: Annotated[float, Field(gt=0, description="distance threshold t, metres")] = 0.8
    min_size: Annotated[int, Field(ge=1, description="smallest cluster kept, points")] = 100
    maps: tuple[tuple[NonNegativeInt, ...], ...] = ()
    mc_mode: Literal["map", "neighbour"] = "map"
    backend: Literal["numba", "scipy"] = "numba"
    main_param: ClassVar[str] = "threshold_m"
    sweep_range: ClassVar[tuple[float, float, float]] = (0.2, 1.5, 0.05)
    sweep_label: ClassVar[str] = "distance threshold [m]"
    slow: ClassVar[bool] = False

    @field_validator("maps")
    @classmethod
    def _check_maps(cls, maps: tuple[tuple[int, ...], ...]) -> tuple[tuple[int, ...], ...]:
        for m in maps:
            check_map(m)
        return maps

    def segment(self, image: RangeImage, points: np.ndarray, ground: Ground | None) -> np.ndarray:
        if self.backend == "scipy":
            left_out, attached = ground_parts(ground)
            mask = image.ranges > 0 if left_out is None else (image.ranges > 0) & ~left_out
            labels = flic_labels_scipy(
                image.ranges,
                image.elevation,
                self.threshold_m,
                self.min_size,
                self.maps,
                self.mc_mode,
                mask,
                image.point_counts(),
                attached,
                image.azimuth_offset,
            )
            return image.point_labels(labels)
        key = (maps_key(self.maps), self.mc_mode)
        t2 = float(self.threshold_m) ** 2
        return segment_image(image, ground, cached_sets(*key), key, DISTANCE, t2, self.min_size)


def flic_labels_scipy(
    ranges: np.ndarray,
    elevation: np.ndarray,
    threshold_m: float = Flic.threshold_m,
    min_size: int = Flic.min_size,
    maps: tuple = Flic.maps,
    mc_mode: str = Flic.mc_mode,
    mask: np.ndarray | None = None,
    weights: np.ndarray | None = None,
    attached: np.ndarray | None = None,
    azimuth_offset: np.ndarray | None = None,
) -> np.ndarray:
    """FLIC the way the paper implements it, with scipy: same result as :func:`flic_labels`.

    The direct connections become a super-sized binary image (measurements on even rows and
    columns, a "connected" pixel between each linked pair) labelled by ``scipy.ndimage.label``
    with 4-connectivity; the 360 deg seam and every Map Connection then add pairs of direct
    labels, merged by ``scipy.sparse.csgraph.connected_components``. Kept as the reference (the
    tests check the numba kernel against it) and as the paper-style peer in benchmarks
    (``backend = "scipy"``). Parameters as :func:`flic_labels`; ``attached``: held pixels, see
    :func:`flic_cli.methods.connections.components`.
    """
    from scipy import ndimage
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from flic_cli.methods.base import drop_small

    d = np.asarray(ranges, dtype=np.float64)
    el = np.asarray(elevation, dtype=np.float64)
    h, w = d.shape
    offset = offset_input(azimuth_offset, h)
    rows_all = np.arange(h)
    valid = d > 0 if mask is None else np.asarray(mask, dtype=bool) & (d > 0)
    t2 = float(threshold_m) ** 2
    steps, offsets, lattice = connection_sets(maps, mc_mode)
    vert = (
        valid[:-1] & valid[1:] & _linked(d[:-1], d[1:], _vertical_cos(el, offset, rows_all, 1), t2)
    )
    right = np.roll(d, -1, axis=1)
    horiz = valid & np.roll(valid, -1, axis=1) & _linked(d, right, _row_cos(el, 1, w), t2)
    big = np.zeros((2 * h - 1, 2 * w), dtype=bool)
    big[0::2, 0::2] = valid
    big[0::2, 1:-1:2] = horiz[:, :-1]
    big[1::2, 0::2] = vert
    big_labels, n = ndimage.label(big)
    direct = big_labels[0::2, 0::2]
    # Extra edges as pairs of pixels (flat indices): the seam, then every Map Connection.
    rows = np.arange(h)
    pairs = [(rows * w + w - 1)[horiz[:, -1]], (rows * w)[horiz[:, -1]]]
    idx = np.arange(h * w).reshape(h, w)
    for (kr, kc), (orow, ocol), lat in zip(steps[1:], offsets[1:], lattice[1:], strict=True):
        if lat:
            r_sel = np.arange(orow % kr, h, kr)
            c_sel = np.arange(ocol % kc, w, kc)
            if r_sel.size == 0 or c_sel.size == 0:
                continue
            sub_d, sub_v, sub_i = (a[np.ix_(r_sel, c_sel)] for a in (d, valid, idx))
            gaps = np.diff(np.append(c_sel, c_sel[0] + w))  # columns to the next lattice column
            ce2 = np.cos(el[r_sel])[:, None] ** 2
            cos_h = ce2 * np.cos(gaps[None, :] * 2.0 * np.pi / w) + (1.0 - ce2)
            nxt = np.roll(np.arange(c_sel.size), -1)
            ok = sub_v & sub_v[:, nxt] & _linked(sub_d, sub_d[:, nxt], cos_h, t2)
            ok &= sub_i != sub_i[:, nxt]
            pairs += [sub_i[ok], sub_i[:, nxt][ok]]
        else:
            r_sel = rows_all
            sub_d, sub_v, sub_i = d, valid, idx
            nd = np.roll(d, -kc, axis=1)
            ok = valid & np.roll(valid, -kc, axis=1) & _linked(d, nd, _row_cos(el, kc, w), t2)
            ok &= idx != np.roll(idx, -kc, axis=1)
            pairs += [idx[ok], np.roll(idx, -kc, axis=1)[ok]]
        step = 1 if lat else kr
        if sub_d.shape[0] > step:
            up, down = sub_d[:-step], sub_d[step:]
            cos_v = _vertical_cos(el, offset, r_sel, step)
            ok = sub_v[:-step] & sub_v[step:] & _linked(up, down, cos_v, t2)
            pairs += [sub_i[:-step][ok], sub_i[step:][ok]]
    flat = direct.reshape(-1)
    a = flat[np.concatenate(pairs[0::2])]
    b = flat[np.concatenate(pairs[1::2])]
    graph = coo_matrix((np.ones(a.size), (a, b)), shape=(n + 1, n + 1))
    _, merged = connected_components(graph, directed=False)
    labels = np.where(flat > 0, merged[flat] + 1, 0)
    if attached is not None and len(attached):  # held pixels take the label standing on them
        held, target = attached[:, 0], attached[:, 1]
        labels[held] = np.where(target >= 0, labels[np.maximum(target, 0)], 0)
    return drop_small(labels, min_size, weights).reshape(h, w)


def flic_labels(
    ranges: np.ndarray,
    elevation: np.ndarray,
    threshold_m: float = Flic.threshold_m,
    min_size: int = Flic.min_size,
    maps: tuple = Flic.maps,
    mc_mode: str = Flic.mc_mode,
    mask: np.ndarray | None = None,
    weights: np.ndarray | None = None,
    azimuth_offset: np.ndarray | None = None,
) -> np.ndarray:
    """FLIC cluster labels of a range image.

    Two measurements ``d1, d2`` separated by the angle ``alpha`` are connected when
    ``d1^2 + d2^2 - 2 cos(alpha) d1 d2 < threshold_m^2`` (the law of cosines: their 3D distance is
    below the threshold). Direct connections are the 4-neighbours with horizontal wrap-around; each
    Map Connection adds the connections of its step (see :func:`connection_sets`). Clusters are the
    connected components; those with fewer than ``min_size`` points are dropped (the points of a
    pixel: ``weights``).

    Parameters
    ----------
    ranges : (H, W) float32 ranges, metres, 0 = no measurement.
    elevation : (H,) row elevations, radians.
    threshold_m : distance threshold t, metres.
    min_size : smallest cluster, in points (the sum of its pixels' ``weights``).
    maps : Map Connection steps, see :func:`connection_sets`.
    mc_mode : ``"map"`` or ``"neighbour"``.
    mask : (H, W) bool, pixels to cluster (default: all valid pixels); a pixel without a range
        is never clustered.
    weights : (H, W) int, points per pixel (:meth:`flic_cli.range_image.RangeImage.point_counts`);
        default 1 per pixel (the minimum size then counts pixels).
    azimuth_offset : (H,) azimuth offset of every row, radians (a pixel's azimuth is its
        column's centre plus it; :attr:`flic_cli.range_image.RangeImage.azimuth_offset`);
        default zeros.

    Returns
    -------
    (H, W) int32, 0 = unclustered, 1..K clusters.
    """
    key = (maps_key(maps), mc_mode)
    skip = None if mask is None else ~np.asarray(mask, dtype=bool)
    return run_kernel(
        ranges,
        elevation,
        cached_sets(*key),
        key,
        DISTANCE,
        float(threshold_m) ** 2,
        min_size,
        skip,
        weights,
        azimuth_offset=azimuth_offset,
    )


BACKENDS = {"numba": flic_labels, "scipy": flic_labels_scipy}
