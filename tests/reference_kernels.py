"""The clustering kernels as they were before issue 11's rework (git 56a0905), kept as references.

The reworked kernels must give the same labels; ``tests/test_methods.py`` and
``tests/test_bridge.py`` compare them on random images, the synthetic sample and the shared frames.
Pixel-by-pixel union-find: every pixel links to its left and upper neighbour in raster order.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from flic_cli.methods.bridge import walk_tables

DISTANCE = 0  # connected when d1^2 + d2^2 - 2 cos(a) d1 d2 < param   (param = t^2)
ANGLE = 1  # connected when atan2(d_min sin a, d_max - d_min cos a) > theta  (param = tan theta)


@njit(cache=True, inline="always")
def _find(parent: np.ndarray, i: int) -> int:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, inline="always")
def _union(parent: np.ndarray, a: int, b: int) -> None:
    ra = _find(parent, a)
    rb = _find(parent, b)
    if ra < rb:
        parent[rb] = ra
    elif rb < ra:
        parent[ra] = rb


@njit(cache=True, inline="always")
def _linked(d1: float, d2: float, c: float, s: float, criterion: int, param: float) -> bool:
    if criterion == DISTANCE:
        return d1 * d1 + d2 * d2 - 2.0 * c * d1 * d2 < param
    # Bogoslavskyi & Stachniss: beta > theta, with d1 the longer and d2 the shorter range.
    big = max(d1, d2)
    small = min(d1, d2)
    den = big - small * c
    if den <= 0.0:  # beta >= 90 deg
        return True
    return small * s > param * den


@njit(cache=True)
def connect_labels(
    ranges: np.ndarray,
    mask: np.ndarray,
    elevation: np.ndarray,
    steps: np.ndarray,
    offsets: np.ndarray,
    lattice: np.ndarray,
    criterion: int,
    param: float,
    min_size: int,
    weights: np.ndarray,
) -> np.ndarray:
    """Connected components of the range-image graph, small components dropped.

    Parameters
    ----------
    ranges : (H, W) float32, metres.
    mask : (H, W) bool, pixels that take part (valid and not ground).
    elevation : (H,) float64 row elevations, radians.
    steps : (M, 2) int64 (row step, column step) of each connection set; (1, 1) = direct neighbours.
    offsets : (M, 2) int64 lattice offset of each set (used when ``lattice[m]``).
    lattice : (M,) bool; True = "map" reading (only the sub-image of every step-th row and column,
        which wraps from its last to its first column), False = "neighbour" reading (every pixel to
        its step-th neighbour below and to the right, wrapping around).
    criterion : DISTANCE or ANGLE.
    param : t^2 (m^2) for DISTANCE, tan(theta) for ANGLE.
    min_size : components whose ``weights`` sum to less are dropped (label 0).
    weights : (H, W) int32, points per pixel (:meth:`flic_cli.range_image.RangeImage.point_counts`);
        all ones = count pixels.

    Returns
    -------
    (H, W) int32 labels, 0 = none, 1..K numbered in raster order of first pixel.
    """
    h, w = ranges.shape
    n = h * w
    r_flat = ranges.reshape(n)
    m_flat = mask.reshape(n)
    w_flat = weights.reshape(n)
    # Invariant: parent[i] <= i (unions hang the larger root under the smaller), so one ascending
    # pass flattens every tree and the root of a component is its first pixel in raster order.
    parent = np.arange(n, dtype=np.int32)
    h_step = 2.0 * np.pi / w

    # Direct connections: each pixel links to its left and upper neighbour in raster order, so the
    # first link is a plain assignment; the 360 deg seam is closed afterwards.
    cv = np.ones(h)
    sv = np.zeros(h)
    ch = np.empty(h)
    sh = np.empty(h)
    for r in range(h):
        if r > 0:
            a = elevation[r - 1] - elevation[r]
            cv[r] = np.cos(a)
            sv[r] = np.sin(abs(a))
        # Two rays of one row, k columns apart: the angle between them shrinks with the row's
        # elevation (cos = cos^2(el) cos(k d_az) + sin^2(el)).
        ce2 = np.cos(elevation[r]) ** 2
        ch[r] = ce2 * np.cos(h_step) + (1.0 - ce2)
        sh[r] = np.sqrt(max(0.0, 1.0 - ch[r] * ch[r]))
    for r in range(h):
        row = r * w
        for c in range(w):
            i = row + c
            if not m_flat[i]:
                continue
            d = r_flat[i]
            if c > 0:
                j = i - 1
                if m_flat[j] and _linked(d, r_flat[j], ch[r], sh[r], criterion, param):
                    parent[i] = _find(parent, j)
            if r > 0:
                j = i - w
                if m_flat[j] and _linked(d, r_flat[j], cv[r], sv[r], criterion, param):
                    _union(parent, i, j)
        if w > 1:
            i = row + w - 1
            if m_flat[i] and m_flat[row]:
                if _linked(r_flat[i], r_flat[row], ch[r], sh[r], criterion, param):
                    _union(parent, i, row)

    # Map Connections (steps[0] is the direct set, done above).
    for m in range(1, steps.shape[0]):
        kr = steps[m, 0]
        kc = steps[m, 1]
        if lattice[m]:
            r0 = offsets[m, 0] % kr
            c0 = offsets[m, 1] % kc
            last = c0 + kc * ((w - 1 - c0) // kc)
            wrap_cols = w - last + c0
            rstep = kr
            cstep = kc
        else:
            r0 = 0
            c0 = 0
            last = w  # never reached: the neighbour reading wraps with the same angle
            wrap_cols = kc
            rstep = 1
            cstep = 1
        for r in range(r0, h, rstep):
            below = r + kr < h
            if below:
                a = elevation[r] - elevation[r + kr]
                cvm = np.cos(a)
                svm = np.sin(abs(a))
            else:
                cvm = 1.0
                svm = 0.0
            ce2 = np.cos(elevation[r]) ** 2
            chm = ce2 * np.cos(kc * h_step) + (1.0 - ce2)
            shm = np.sqrt(max(0.0, 1.0 - chm * chm))
            cw = ce2 * np.cos(wrap_cols * h_step) + (1.0 - ce2)
            sw = np.sqrt(max(0.0, 1.0 - cw * cw))
            row = r * w
            for c in range(c0, w, cstep):
                i = row + c
                if not m_flat[i]:
                    continue
                d1 = r_flat[i]
                if below:
                    j = i + kr * w
                    if m_flat[j] and _linked(d1, r_flat[j], cvm, svm, criterion, param):
                        _union(parent, i, j)
                if lattice[m] and c == last:
                    j = row + c0
                    if j != i and m_flat[j] and _linked(d1, r_flat[j], cw, sw, criterion, param):
                        _union(parent, i, j)
                else:
                    j = row + (c + kc) % w
                    if j != i and m_flat[j] and _linked(d1, r_flat[j], chm, shm, criterion, param):
                        _union(parent, i, j)

    return number_components(parent, m_flat, w_flat, min_size).reshape(h, w)


@njit(cache=True)
def number_components(
    parent: np.ndarray, m_flat: np.ndarray, w_flat: np.ndarray, min_size: int
) -> np.ndarray:
    """Labels from a union-find forest whose roots are their component's first member.

    Parameters
    ----------
    parent : (N,) int32 forest with ``parent[i] <= i`` (modified: flattened).
    m_flat : (N,) bool, the members (others get label 0).
    w_flat : (N,) int32 weight of each member (points per pixel).
    min_size : components whose weights sum to less are dropped.

    Returns
    -------
    (N,) int32 labels 1..K numbered in order of each component's first member, 0 = none.
    """
    n = parent.size
    # Flatten (ascending order, see the invariant) and sum the weights in one pass.
    size = np.zeros(n, dtype=np.int64)
    for i in range(n):
        if m_flat[i]:
            root = parent[parent[i]]
            parent[i] = root
            size[root] += w_flat[i]
    # Number the kept components in order of their first member; size[root] < 0 marks a
    # numbered root (-label).
    labels = np.zeros(n, dtype=np.int32)
    k = 0
    for i in range(n):
        if m_flat[i]:
            root = parent[i]
            s = size[root]
            if s < 0:
                labels[i] = -s
            elif s >= min_size:
                k += 1
                size[root] = -k
                labels[i] = k
    return labels


def flic_labels(
    ranges, elevation, threshold_m, min_size, maps=(), mc_mode="map", mask=None, weights=None
):
    """FLIC labels per pixel as before (``mask``: the nodes; default the valid pixels)."""
    from flic_cli.methods.flic import connection_sets

    ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    mask = ranges > 0 if mask is None else np.ascontiguousarray(mask, dtype=bool)
    steps, offsets, lattice = connection_sets(maps, mc_mode)
    return connect_labels(
        ranges, mask, np.asarray(elevation, dtype=np.float64), steps, offsets, lattice,
        DISTANCE, float(threshold_m) ** 2, int(min_size), _weights(weights, ranges.shape),
    )  # fmt: skip


def bogoslavskyi_labels(ranges, elevation, angle_deg, min_size, mask=None, weights=None):
    """Bogoslavskyi labels per pixel as before."""
    from flic_cli.methods.flic import connection_sets

    ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    mask = ranges > 0 if mask is None else np.ascontiguousarray(mask, dtype=bool)
    steps, offsets, lattice = connection_sets(())
    return connect_labels(
        ranges, mask, np.asarray(elevation, dtype=np.float64), steps, offsets, lattice,
        ANGLE, float(np.tan(np.radians(angle_deg))), int(min_size),
        _weights(weights, ranges.shape),
    )  # fmt: skip


def _weights(weights, shape):
    if weights is None:
        return np.ones(shape, dtype=np.int32)
    return np.ascontiguousarray(weights, dtype=np.int32)


def segment(method, image, ground):
    """Per-point labels of a Flic, Bogoslavskyi or Bridge method as its ``segment`` gave them
    before."""
    from flic_cli.methods import Bogoslavskyi, Bridge, Flic

    mask = image.ranges > 0 if ground is None else (image.ranges > 0) & ~ground
    weights = image.point_counts()
    if isinstance(method, Flic):
        labels = flic_labels(
            image.ranges, image.elevation, method.threshold_m, method.min_size, method.maps,
            method.mc_mode, mask, weights,
        )  # fmt: skip
    elif isinstance(method, Bogoslavskyi):
        labels = bogoslavskyi_labels(
            image.ranges, image.elevation, method.angle_deg, method.min_size, mask, weights
        )
    elif isinstance(method, Bridge):
        labels = bridge_labels(
            image.ranges, image.elevation, method.threshold_m, method.gamma_deg,
            method.reach_px, method.min_size, mask, weights,
        )  # fmt: skip
    else:
        raise TypeError(type(method))
    flat = labels.reshape(-1)
    out = np.zeros(image.point_pixel.size, dtype=np.int32)
    has = image.point_pixel >= 0
    out[has] = flat[image.point_pixel[has]]
    return out


# ---- Bridge (flic_cli/methods/bridge.py at 56a0905) ----


@njit(cache=True, inline="always")
def _walk(
    rr: np.ndarray,
    raw: np.ndarray,
    w: int,
    r: int,
    c: int,
    d: float,
    tp: float,
    tp2: float,
    j1: int,
    dr: int,
    dc: int,
    kmax: int,
    cos_row: np.ndarray,
    sin_row: np.ndarray,
) -> int:
    """Flat index of the measurement the walk from (r, c) links to, or -1 (module docstring).

    ``rr`` holds the ranges of the nodes (0 elsewhere), ``raw`` every range (a pixel outside the
    mask, e.g. ground, still shows free space). ``j1`` is the flat index of the first step (the
    caller knows it without a modulo).
    """
    if kmax < 1 or d * sin_row[1] >= tp:
        return -1
    dq = np.float64(rr[j1])
    if dq > 0.0:
        if d * d + dq * dq - 2.0 * cos_row[1] * d * dq < tp2:
            return j1
        if dq > d:
            return -1
    elif raw[j1] > d:
        return -1
    for k in range(2, kmax + 1):
        if d * sin_row[k] >= tp:
            return -1
        c2 = c + k * dc
        if c2 < 0:
            c2 += w
        elif c2 >= w:
            c2 -= w
        j = (r + k * dr) * w + c2
        dq = np.float64(rr[j])
        if dq > 0.0:
            if d * d + dq * dq - 2.0 * cos_row[k] * d * dq < tp2:
                return j
            if dq > d:
                return -1
        elif raw[j] > d:
            return -1
    return -1


@njit(cache=True)
def bridge_kernel(
    ranges: np.ndarray,
    mask: np.ndarray,
    elevation: np.ndarray,
    threshold: float,
    sin_gamma: float,
    reach: int,
    min_size: int,
    weights: np.ndarray,
) -> np.ndarray:
    """Connected components of the Bridge graph (module docstring), small ones dropped.

    Parameters
    ----------
    ranges : (H, W) float32, metres, 0 = none.
    mask : (H, W) bool, pixels that take part.
    elevation : (H,) float64, radians.
    threshold : threshold_m, metres.
    sin_gamma : sin(gamma_deg).
    reach : reach_px >= 1.
    min_size : smallest component kept, in summed ``weights``.
    weights : (H, W) int32 points per pixel.

    Returns
    -------
    (H, W) int32 labels, 0 = none, 1..K in raster order of each component's first pixel.
    """
    h, w = ranges.shape
    n = h * w
    raw = ranges.reshape(n)
    mask_flat = mask.reshape(n)
    # the nodes' ranges (0 elsewhere); a plain loop: numba's np.where with a scalar is 20x slower
    rr = np.empty(n, dtype=np.float32)
    for i in range(n):
        rr[i] = raw[i] if mask_flat[i] else np.float32(0.0)
    m_flat = rr > 0
    # Invariant: parent[i] <= i (a root always hangs under the smaller root), so the root of a
    # component is its first pixel in raster order (see number_components). The union steps are
    # written out below: numba compiles a helper that updates `parent` and returns the new root
    # into far slower code.
    parent = np.arange(n, dtype=np.int32)
    cos_t, sin_t = walk_tables(elevation, w, reach)
    k_row = min(reach, w - 1)
    for r in range(h):
        k_up = min(reach, r)
        k_diag = min(k_up, k_row)
        c_l = cos_t[0, r]
        s_l = sin_t[0, r]
        c_u = cos_t[1, r]
        s_u = sin_t[1, r]
        c_ul = cos_t[2, r]
        s_ul = sin_t[2, r]
        c_ur = cos_t[3, r]
        s_ur = sin_t[3, r]
        row = r * w
        for c in range(w):
            i = row + c
            d = np.float64(rr[i])
            if d <= 0.0:
                continue
            tp = max(threshold, d * sin_gamma)
            tp2 = tp * tp
            # The walks go to earlier pixels, except left walks across the seam, which reach the
            # last k_row columns of the row: only there can i already have been joined.
            root = i if c < w - k_row else _find(parent, i)
            j_left = i - 1 if c > 0 else i + w - 1
            j = _walk(rr, raw, w, r, c, d, tp, tp2, j_left, 0, -1, k_row, c_l, s_l)
            inside = j == j_left
            if j >= 0:
                rj = _find(parent, j)
                if rj < root:
                    parent[root] = rj
                    root = rj
                elif rj > root:
                    parent[rj] = root
            if k_up == 0:
                continue
            j_up = i - w
            j = _walk(rr, raw, w, r, c, d, tp, tp2, j_up, -1, 0, k_up, c_u, s_u)
            if j >= 0:
                rj = _find(parent, j)
                if rj < root:
                    parent[root] = rj
                    root = rj
                elif rj > root:
                    parent[rj] = root
            if inside and j == j_up:
                continue
            j1 = j_up - 1 if c > 0 else j_up + w - 1
            j = _walk(rr, raw, w, r, c, d, tp, tp2, j1, -1, -1, k_diag, c_ul, s_ul)
            if j >= 0:
                rj = _find(parent, j)
                if rj < root:
                    parent[root] = rj
                    root = rj
                elif rj > root:
                    parent[rj] = root
            j1 = j_up + 1 if c < w - 1 else j_up - w + 1
            j = _walk(rr, raw, w, r, c, d, tp, tp2, j1, -1, 1, k_diag, c_ur, s_ur)
            if j >= 0:
                rj = _find(parent, j)
                if rj < root:
                    parent[root] = rj
                    root = rj
                elif rj > root:
                    parent[rj] = root
    return number_components(parent, m_flat, weights.reshape(n), min_size).reshape(h, w)


def bridge_labels(ranges, elevation, threshold_m, gamma_deg, reach_px, min_size, mask, weights):
    """Bridge labels per pixel as before (``mask``: pixels that take part)."""
    ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    mask = ranges > 0 if mask is None else np.ascontiguousarray(mask, dtype=bool)
    return bridge_kernel(
        ranges, mask, np.asarray(elevation, dtype=np.float64), float(threshold_m),
        float(np.sin(np.radians(gamma_deg))), int(reach_px), int(min_size),
        _weights(weights, ranges.shape),
    )  # fmt: skip
