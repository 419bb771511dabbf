"""The graph of FLIC and Bogoslavskyi on the range image: direct 4-neighbours with the 360 deg
seam, and FLIC's Map Connections; its components by the engine of
:mod:`flic_cli.methods.engine`, its edges by a test of :mod:`flic_cli.methods.criteria`.

Row by row, loops that LLVM vectorises compute the node ranges and the left and up links of
every pixel (:func:`_link_rows`, the criterion's test applied to the whole row), the engine
labels the row by runs (:func:`flic_cli.methods.engine.label_row`), and the seam merges the
first and last pixel of the row. A Map Connection can only change anything between pixels in
different components of the direct connections: each pair row's flag "different components" is
computed over the whole row (vectorised), packed, masked to the connection's columns, and only
the flagged pairs are tested and merged.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from flic_cli.bitwords import pack, trailing_zeros
from flic_cli.methods.base import ground_parts, point_weights
from flic_cli.methods.criteria import ANGLE, DISTANCE, angle_edge, distance_edge, edge, ray_angle
from flic_cli.methods.engine import (
    attach,
    attached_input,
    kernel_inputs,
    label_row,
    number,
    pixel_output,
    point_output,
    run_buffers,
    union,
)

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground
    from flic_cli.range_image import RangeImage

__all__ = [
    "ANGLE",
    "DISTANCE",
    "angle_tables",
    "cached_angles",
    "connect",
    "connect_points",
    "run_kernel",
    "segment_image",
]


@njit(cache=True)
def angle_tables(
    elevation: np.ndarray,
    azimuth_offset: np.ndarray,
    width: int,
    steps: np.ndarray,
    offsets: np.ndarray,
    lattice: np.ndarray,
    criterion: int,
) -> np.ndarray:
    """cos and sin of the angles between the rays of every connection, per set and row.

    Parameters
    ----------
    elevation : (H,) float64 row elevations, radians.
    azimuth_offset : (H,) float64 azimuth offset of every row, radians (a pixel's azimuth is its
        column's centre plus it): the rays of vertical neighbours are
        :func:`flic_cli.methods.criteria.ray_angle` apart, those of one row only the columns'
        azimuth difference.
    width : W, columns over 360 deg.
    steps, offsets, lattice : the connection sets (see :func:`connect`).
    criterion : DISTANCE (the sines of vertical angles are not needed: left 0) or ANGLE.

    Returns
    -------
    (M, H, 6) float64: for set m and row r, cos and sin of the angle to the pixel ``steps[m, 0]``
    rows below (index 0, 1; 1 and 0 where there is none), to the pixel ``steps[m, 1]`` columns to
    the right (2, 3) and, in a lattice, from its last column to its first across the seam (4, 5).
    For the direct set (m = 0) the vertical angle is the one to the row *above* (r - 1). A lattice
    fills only its own rows.
    """
    h = elevation.size
    n_sets = steps.shape[0]
    out = np.zeros((n_sets, h, 6))
    h_step = 2.0 * np.pi / width
    # Two rays of one row, k columns apart: the angle between them shrinks with the row's
    # elevation (cos = cos^2(el) cos(k d_az) + sin^2(el)).
    ce2 = np.empty(h)
    for r in range(h):
        ce2[r] = np.cos(elevation[r]) ** 2
    ck = np.cos(h_step)
    for r in range(h):  # the direct connections
        out[0, r, 0] = 1.0
        if r > 0:
            a = ray_angle(elevation[r - 1], elevation[r], azimuth_offset[r - 1], azimuth_offset[r])
            out[0, r, 0] = np.cos(a)
            if criterion == ANGLE:
                out[0, r, 1] = np.sin(abs(a))
        ch = ce2[r] * ck + (1.0 - ce2[r])
        out[0, r, 2] = ch
        out[0, r, 3] = np.sqrt(max(0.0, 1.0 - ch * ch))
    for m in range(1, n_sets):
        kr = steps[m, 0]
        kc = steps[m, 1]
        if lattice[m]:
            r0 = offsets[m, 0] % kr
            c0 = offsets[m, 1] % kc
            last = c0 + kc * ((width - 1 - c0) // kc)
            wrap_cols = width - last + c0
            rstep = kr
        else:
            r0 = 0
            wrap_cols = kc  # the neighbour reading wraps with the same angle
            rstep = 1
        ckm = np.cos(kc * h_step)
        cwm = np.cos(wrap_cols * h_step)
        for r in range(r0, h, rstep):
            if r + kr < h:
                a = ray_angle(
                    elevation[r], elevation[r + kr], azimuth_offset[r], azimuth_offset[r + kr]
                )
                out[m, r, 0] = np.cos(a)
                if criterion == ANGLE:
                    out[m, r, 1] = np.sin(abs(a))
            else:
                out[m, r, 0] = 1.0
            chm = ce2[r] * ckm + (1.0 - ce2[r])
            out[m, r, 2] = chm
            out[m, r, 3] = np.sqrt(max(0.0, 1.0 - chm * chm))
            cw = ce2[r] * cwm + (1.0 - ce2[r])
            out[m, r, 4] = cw
            out[m, r, 5] = np.sqrt(max(0.0, 1.0 - cw * cw))
    return out


@njit(cache=True, inline="always")
def _link_row(
    out: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    cos_a: float,
    sin_a: float,
    criterion: int,
    param: float,
) -> None:
    """``out[c] = a[c] and b[c] are linked`` for node ranges (0 = no node); the criterion is
    chosen outside the loop and its test is branch-free, so that LLVM vectorises the loop."""
    if criterion == DISTANCE:
        for c in range(out.size):
            d1 = a[c]
            d2 = b[c]
            out[c] = (d1 > 0) & (d2 > 0) & distance_edge(d1, d2, cos_a, param)
    else:
        for c in range(out.size):
            d1 = a[c]
            d2 = b[c]
            out[c] = (d1 > 0) & (d2 > 0) & angle_edge(d1, d2, cos_a, sin_a, param)


@njit(cache=True, inline="always")
def _link_rows(
    left: np.ndarray,
    up: np.ndarray,
    d: np.ndarray,
    above: np.ndarray,
    ch: float,
    sh: float,
    cv: float,
    sv: float,
    criterion: int,
    param: float,
) -> None:
    """``left[c]``: (r, c) linked to (r, c - 1), for c >= 1; ``up[c]``: (r, c) linked to the pixel
    above, ``above[c]``; one vectorised pass (see :func:`_link_row`)."""
    if criterion == DISTANCE:
        for c in range(1, d.size):
            d1 = d[c]
            d2 = d[c - 1]
            d3 = above[c]
            left[c] = (d1 > 0) & (d2 > 0) & distance_edge(d1, d2, ch, param)
            up[c] = (d1 > 0) & (d3 > 0) & distance_edge(d1, d3, cv, param)
    else:
        for c in range(1, d.size):
            d1 = d[c]
            d2 = d[c - 1]
            d3 = above[c]
            left[c] = (d1 > 0) & (d2 > 0) & angle_edge(d1, d2, ch, sh, param)
            up[c] = (d1 > 0) & (d3 > 0) & angle_edge(d1, d3, cv, sv, param)
    d1 = d[0]
    d3 = above[0]
    up[0] = (d1 > 0) & (d3 > 0) & edge(d1, d3, cv, sv, criterion, param)


@njit(cache=True)
def _differ(flags: np.ndarray, a: np.ndarray, b: np.ndarray) -> None:
    """``flags[c]``: ``a[c]`` and ``b[c]`` are nodes (label != 0) of different components;
    branch-free, so that LLVM vectorises it."""
    for c in range(a.size):
        x = a[c]
        y = b[c]
        flags[c] = (x != y) & (x != 0) & (y != 0)


@njit(cache=True)
def _join(
    words: np.ndarray,
    mask: np.ndarray,
    comp: np.ndarray,
    nodes: np.ndarray,
    parent: np.ndarray,
    row: int,
    partner: int,
    wrap: int,
    w: int,
    cos_a: float,
    sin_a: float,
    criterion: int,
    param: float,
) -> None:
    """Merge the linked pairs (row + c, partner + c) of pixels in different direct components,
    for the columns c set in ``words & mask``; a partner column past ``wrap`` is taken ``w``
    columns back (the 360 deg seam). ``words``: the packed flags "different components" of the
    pairs (:func:`_differ`, then :func:`flic_cli.bitwords.pack`); only the flagged pairs are
    tested (by ``criterion``, at the angle cos ``cos_a``, sin ``sin_a``)."""
    one = np.uint64(1)
    for k in range(words.size):
        bits = words[k] & mask[k]
        while bits:
            c = 64 * k + np.int64(trailing_zeros(bits))
            bits &= bits - one
            i = row + c
            j = partner + c - (w if c >= wrap else 0)
            if edge(nodes[i], nodes[j], cos_a, sin_a, criterion, param):
                union(parent, comp[i], comp[j])


@njit(cache=True)
def _lattice_mask(mask: np.ndarray, first: int, step: int, count: int) -> None:
    """Set bits ``first + q step``, q < count, of the words ``mask`` (cleared first)."""
    mask[:] = 0
    for q in range(count):
        c = first + q * step
        mask[c >> 6] |= np.uint64(1) << np.uint64(c & 63)


@njit(cache=True)
def components(
    ranges: np.ndarray,
    skip: np.ndarray,
    use_skip: bool,
    steps: np.ndarray,
    offsets: np.ndarray,
    lattice: np.ndarray,
    angles: np.ndarray,
    criterion: int,
    param: float,
    min_size: int,
    weights: np.ndarray,
    use_weights: bool,
    attached: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Provisional label of every pixel (0 = no node) and the final label of each provisional
    label (0 = dropped): the components of the graph of direct neighbours and connection sets.

    Parameters
    ----------
    ranges : (H, W) float32, metres, 0 = no measurement.
    skip : (H, W) bool, pixels that do not take part even with a range (e.g. ground); read only
        when ``use_skip``.
    use_skip : whether to read ``skip``.
    steps : (M, 2) int64 (row step, column step) of each connection set; (1, 1) = direct neighbours.
    offsets : (M, 2) int64 lattice offset of each set (used when ``lattice[m]``).
    lattice : (M,) bool; True = "map" reading (only the sub-image of every step-th row and column,
        which wraps from its last to its first column), False = "neighbour" reading (every pixel to
        its step-th neighbour below and to the right, wrapping around).
    angles : :func:`angle_tables` of these sets.
    criterion : DISTANCE or ANGLE.
    param : t^2 (m^2) for DISTANCE, tan(theta) for ANGLE.
    min_size : components whose ``weights`` sum to less are dropped (label 0).
    weights : (H, W) int32, points per pixel (:meth:`flic_cli.range_image.RangeImage.point_counts`);
        read only when ``use_weights`` (else every pixel counts 1).
    use_weights : whether to read ``weights``.
    attached : (K, 3) int64, held pixels (left out by ``skip``) that take the component of the
        pixel standing on them, with their points (:attr:`flic_cli.ground.base.Ground.
        attached`; (0, 3) for none).
    """
    h, w = ranges.shape
    n = h * w
    rf = ranges.reshape(n)
    sf = skip.reshape(skip.size)  # a (1, 1) stand-in when not use_skip
    wf = weights.reshape(weights.size)
    nodes = np.empty(n, dtype=np.float32)  # node ranges, 0 elsewhere
    (
        labels, parent, size, node, left, up, node_w, left_w, left_up_w, up_w, starts, ends, acc
    ) = run_buffers(n, w)  # fmt: skip
    nw = node_w.size - 1
    n_labels = np.uint64(0)
    for r in range(h):
        row = r * w
        d = nodes[row : row + w]
        if use_skip:
            for c in range(w):
                x = rf[row + c]
                ok = (x > 0) & ~sf[row + c]
                d[c] = x if ok else np.float32(0.0)
                node[c] = ok
        else:
            for c in range(w):
                x = rf[row + c]
                d[c] = x if x > 0 else np.float32(0.0)
                node[c] = x > 0
        ch = angles[0, r, 2]
        sh = angles[0, r, 3]
        if r > 0:
            above = nodes[row - w : row]
            _link_rows(
                left[:w], up[:w], d, above, ch, sh, angles[0, r, 0], angles[0, r, 1],
                criterion, param,
            )  # fmt: skip
        elif w > 1:
            _link_row(left[1:w], d[1:], d[:-1], ch, sh, criterion, param)
        n_labels = label_row(
            r, w, n_labels, d, node, left, up, node_w, left_w, left_up_w, up_w, starts, ends, acc,
            labels, parent, size, wf, use_weights,
        )  # fmt: skip
        left_w, left_up_w = left_up_w, left_w
        # the 360 deg seam
        if w > 1 and d[0] > 0 and d[w - 1] > 0:
            if edge(d[w - 1], d[0], ch, sh, criterion, param):  # one column apart
                union(parent, labels[row + w - 1], labels[row])

    nl = np.int64(n_labels)
    # Map Connections: only pairs in different components of the direct connections can change
    # anything. comp holds the root label of each pixel's direct component (0 = no node); rows
    # of flags "different components" are computed whole (vectorised), packed and masked to the
    # connection's columns; only the few flagged pairs are tested.
    if steps.shape[0] > 1:
        for lab_ in range(1, nl + 1):
            parent[lab_] = parent[parent[lab_]]
        comp = np.empty(n, dtype=np.uint32)
        for i in range(n):
            comp[i] = parent[labels[i]]
        mask_v = np.empty(nw, dtype=np.uint64)
        mask_h = np.empty(nw, dtype=np.uint64)
        flag_w = np.empty(nw, dtype=np.uint64)
        flags = np.zeros(64 * nw + 8, dtype=np.uint8)
    # Each join: the flags of the pair rows (vectorised), packed, then the flagged pairs. The two
    # readings keep loops of their own: one loop branching on the reading per row ran 4 % slower
    # (FLIC 14 MC, scripts/kernel_revisions.py; results/benchmark/revisions/README.md).
    for m in range(1, steps.shape[0]):
        kr = steps[m, 0]
        kc = steps[m, 1]
        if lattice[m]:
            # the rows r0, r0 + kr, ... and in each the lattice columns c0, c0 + kc, ..., last
            # (mask_v; mask_h without last)
            r0 = offsets[m, 0] % kr
            c0 = offsets[m, 1] % kc
            if c0 >= w:
                continue  # no lattice column
            last = c0 + kc * ((w - 1 - c0) // kc)
            cols = (last - c0) // kc + 1
            _lattice_mask(mask_v, c0, kc, cols)
            _lattice_mask(mask_h, c0, kc, cols - 1)
            for r in range(r0, h, kr):
                row = r * w
                if r + kr < h:  # down: (r, c) to (r + kr, c)
                    below = row + kr * w
                    _differ(flags[:w], comp[row : row + w], comp[below : below + w])
                    pack(flags[: 64 * nw], flag_w)
                    _join(
                        flag_w, mask_v, comp, nodes, parent, row, below, w, w,
                        angles[m, r, 0], angles[m, r, 1], criterion, param,
                    )  # fmt: skip
                if cols > 1:
                    # right: the pairs (c, c + kc) of lattice columns c < last
                    i0 = row + c0
                    i1 = row + last - kc + 1
                    _differ(flags[c0 : last - kc + 1], comp[i0:i1], comp[i0 + kc : i1 + kc])
                    pack(flags[: 64 * nw], flag_w)
                    _join(
                        flag_w, mask_h, comp, nodes, parent, row, row + kc, w, w,
                        angles[m, r, 2], angles[m, r, 3], criterion, param,
                    )  # fmt: skip
                    # from the last lattice column across the seam to the first
                    i = row + last
                    j = row + c0
                    if comp[i] != comp[j] and comp[i] != 0 and comp[j] != 0:
                        if edge(nodes[i], nodes[j], angles[m, r, 4], angles[m, r, 5],
                                   criterion, param):  # fmt: skip
                            union(parent, comp[i], comp[j])
        else:
            shift = kc % w
            _lattice_mask(mask_v, 0, 1, w)
            for r in range(h):
                row = r * w
                if r + kr < h:  # down: (r, c) to (r + kr, c)
                    below = row + kr * w
                    _differ(flags[:w], comp[row : row + w], comp[below : below + w])
                    pack(flags[: 64 * nw], flag_w)
                    _join(
                        flag_w, mask_v, comp, nodes, parent, row, below, w, w,
                        angles[m, r, 0], angles[m, r, 1], criterion, param,
                    )  # fmt: skip
                if shift:  # right: (c, c + kc), wrapping (shift 0: every pixel its own neighbour)
                    rest = w - shift
                    _differ(flags[:rest], comp[row : row + rest], comp[row + shift : row + w])
                    _differ(flags[rest:w], comp[row + rest : row + w], comp[row : row + shift])
                    pack(flags[: 64 * nw], flag_w)
                    _join(
                        flag_w, mask_v, comp, nodes, parent, row, row + shift, rest, w,
                        angles[m, r, 2], angles[m, r, 3], criterion, param,
                    )  # fmt: skip

    attach(labels, size, attached)
    return labels[:n], number(parent, size, nl, min_size)


@njit(cache=True)
def connect(*args) -> np.ndarray:  # noqa: ANN002
    """Connected components of the range-image graph, small components dropped, per pixel:
    (H, W) int32 labels, 0 = none, 1..K numbered in raster order of first pixel; the arguments
    of :func:`components`."""
    labels, final = components(*args)
    return pixel_output(labels, final).reshape(args[0].shape)


@njit(cache=True)
def connect_points(point_pixel: np.ndarray, *args) -> np.ndarray:  # noqa: ANN002
    """:func:`connect`, but the label of every point: ``labels[point_pixel]`` (0 where
    ``point_pixel`` is negative: a point without a pixel), without the per-pixel image."""
    labels, final = components(*args)
    return point_output(labels, final, point_pixel)


#: (elevation bytes, azimuth offset bytes, width, sets key, criterion) -> angle_tables; cleared
#: when full
_ANGLES: dict[tuple, np.ndarray] = {}


def cached_angles(
    elevation: np.ndarray,
    azimuth_offset: np.ndarray,
    width: int,
    sets: tuple,
    key: object,
    criterion: int,
) -> np.ndarray:
    """:func:`angle_tables`, computed once per elevation, azimuth offsets, width and connection
    sets (``key`` names the sets, e.g. the maps and reading; ``sets`` is ``(steps, offsets,
    lattice)``)."""
    k = (elevation.tobytes(), azimuth_offset.tobytes(), width, key, criterion)
    out = _ANGLES.get(k)
    if out is None:
        if len(_ANGLES) >= 64:
            _ANGLES.clear()
        out = _ANGLES[k] = angle_tables(elevation, azimuth_offset, width, *sets, criterion)
    return out


#: rows -> (rows,) read-only zeros: the azimuth offsets of an image without them
_NO_OFFSETS: dict[int, np.ndarray] = {}


def offset_input(azimuth_offset: np.ndarray | None, h: int) -> np.ndarray:
    """The (H,) contiguous float64 azimuth offsets of the rows (zeros for None); shape checked."""
    if azimuth_offset is None:
        zeros = _NO_OFFSETS.get(h)
        if zeros is None:
            zeros = _NO_OFFSETS[h] = np.zeros(h)
            zeros.flags.writeable = False
        return zeros
    offset = np.ascontiguousarray(azimuth_offset, dtype=np.float64)
    if offset.shape != (h,):
        raise ValueError(f"azimuth_offset has shape {offset.shape}, the image {h} rows")
    return offset


def run_kernel(
    ranges: np.ndarray,
    elevation: np.ndarray,
    sets: tuple[np.ndarray, np.ndarray, np.ndarray],
    key: object,
    criterion: int,
    param: float,
    min_size: int,
    skip: np.ndarray | None = None,
    weights: np.ndarray | None = None,
    point_pixel: np.ndarray | None = None,
    attached: np.ndarray | None = None,
    azimuth_offset: np.ndarray | None = None,
) -> np.ndarray:
    """Labels per pixel (:func:`connect`) or, given ``point_pixel``, per point
    (:func:`connect_points`).

    Parameters
    ----------
    ranges : (H, W) ranges, metres, 0 = none.
    elevation : (H,) row elevations, radians.
    sets : ``(steps, offsets, lattice)`` of the connections, see :func:`connect`.
    key : a hashable name of ``sets`` (for the cache of :func:`cached_angles`).
    criterion, param, min_size : see :func:`connect`.
    skip : (H, W) bool, pixels left out even with a range (ground), or None.
    weights : (H, W) int, points per pixel, or None (1 per pixel).
    point_pixel : (N,) int64 pixel of every point (-1: none), or None for per-pixel labels.
    attached : (K, 3) held pixels, see :func:`connect`, or None.
    azimuth_offset : (H,) azimuth offset of every row, radians
        (:attr:`flic_cli.range_image.RangeImage.azimuth_offset`), or None (zeros).
    """
    ranges, elevation, skip, use_skip, weights, use_weights = kernel_inputs(
        ranges, elevation, skip, weights
    )
    offset = offset_input(azimuth_offset, elevation.size)
    angles = cached_angles(elevation, offset, ranges.shape[1], sets, key, criterion)
    args = (
        ranges,
        skip,
        use_skip,
        *sets,
        angles,
        criterion,
        float(param),
        int(min_size),
        weights,
        use_weights,
        attached_input(attached),
    )
    if point_pixel is None:
        return connect(*args)
    return connect_points(np.ascontiguousarray(point_pixel, dtype=np.int64), *args)


def segment_image(
    image: RangeImage,
    ground: Ground | None,
    sets: tuple[np.ndarray, np.ndarray, np.ndarray],
    key: object,
    criterion: int,
    param: float,
    min_size: int,
) -> np.ndarray:
    """:func:`run_kernel` on a method's input: (N,) labels of the points of ``image`` (its
    ranges, row elevations and azimuth offsets, points per pixel), the pixels ``ground`` leaves
    out skipped and its held pixels attached (:func:`flic_cli.methods.base.ground_parts`)."""
    left_out, attached = ground_parts(ground)
    return run_kernel(
        image.ranges,
        image.elevation,
        sets,
        key,
        criterion,
        param,
        min_size,
        left_out,
        point_weights(image),
        image.point_pixel,
        attached,
        image.azimuth_offset,
    )
