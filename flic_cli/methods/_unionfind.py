"""Numba kernel: connected components of the range-image graph of FLIC and Bogoslavskyi.

Why not ``scipy.ndimage.label``: FLIC's and Bogoslavskyi's connectivity is decided per *edge* (a
distance or angle test between two measurements), not per pixel. ``ndimage.label`` needs the
paper's super-sized image (4x the pixels, then extra passes for the 360 deg seam and the Map
Connections) and ``scipy.sparse.csgraph.connected_components`` needs the edge list built as a
sparse matrix first; both cost more than the clustering itself. The tests check this kernel against
``connected_components`` of a brute-force graph built from the 3D coordinates, and against the
previous pixel-by-pixel union-find kept in the tests.

How it works (two-pass labelling over *runs*, the classic scheme for binary images with the
pixel test replaced by an edge test):

1. Row by row, branch-free loops that LLVM vectorises: the node ranges (the range where the pixel
   takes part, 0 elsewhere: no measurement, or excluded e.g. as ground), the link to the left
   neighbour and the link to the neighbour above of every pixel.
2. One loop over the row's pixels: a *run* is a maximal stretch of nodes linked to their left
   neighbours; every run gets a new provisional label (so labels are numbered in raster order of
   the runs' first pixels) and the weight of its pixels. A vertical link merges the run with the
   run above, unless the square of links to its left already did (left, up-left and up-left to up
   linked).
3. The 360 deg seam and the Map Connections merge labels of linked pixel pairs; a pair whose labels
   already share a parent is skipped before the link is even tested.
4. One pass over the provisional labels (few: a run is ~10 pixels) flattens the union-find forest,
   sums the weights of each component and numbers the kept components 1..K in order of their
   smallest label, i.e. of their first pixel in raster order; then labels per pixel or per point.

Union by the smaller label keeps ``parent[l] <= l``, so one ascending pass flattens the forest and
a component's root is its first run.
"""

from __future__ import annotations

import numpy as np
from numba import njit

DISTANCE = 0  # connected when d1^2 + d2^2 - 2 cos(a) d1 d2 < param   (param = t^2)
ANGLE = 1  # connected when atan2(d_min sin a, d_max - d_min cos a) > theta  (param = tan theta)


@njit(cache=True, inline="always")
def _find(parent: np.ndarray, i: int) -> int:
    """Root of ``i`` (path halving)."""
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, inline="always")
def _union(parent: np.ndarray, a: int, b: int) -> None:
    """Merge the sets of ``a`` and ``b``: the larger root hangs under the smaller one."""
    if parent[a] == parent[b]:
        return
    ra = _find(parent, a)
    rb = _find(parent, b)
    if ra < rb:
        parent[rb] = ra
    elif rb < ra:
        parent[ra] = rb


@njit(cache=True, inline="always")
def _linked(d1, d2, c: float, s: float, criterion: int, param: float) -> bool:  # noqa: ANN001
    """Whether two node ranges ``d1``, ``d2`` (float32, > 0) at the angle (cos ``c``, sin ``s``)
    are connected. The operations and their order are the ones the labels were defined with."""
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
def angle_tables(
    elevation: np.ndarray,
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
            a = elevation[r - 1] - elevation[r]
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
                a = elevation[r] - elevation[r + kr]
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
    """``out[c] = a[c] and b[c] are linked`` for node ranges (0 = no node); branch-free, so that
    LLVM vectorises it. The tests are :func:`_linked`'s, operation for operation."""
    if criterion == DISTANCE:
        for c in range(out.size):
            d1 = a[c]
            d2 = b[c]
            out[c] = (d1 > 0) & (d2 > 0) & (d1 * d1 + d2 * d2 - 2.0 * cos_a * d1 * d2 < param)
    else:
        for c in range(out.size):
            d1 = a[c]
            d2 = b[c]
            big = max(d1, d2)
            small = min(d1, d2)
            den = big - small * cos_a
            out[c] = (d1 > 0) & (d2 > 0) & ((den <= 0.0) | (small * sin_a > param * den))


@njit(cache=True)
def _components(
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
) -> tuple[np.ndarray, np.ndarray]:
    """Provisional label of every pixel (0 = no node) and the final label of each provisional
    label (0 = dropped); parameters as :func:`connect`."""
    h, w = ranges.shape
    n = h * w
    rf = ranges.reshape(n)
    sf = skip.reshape(skip.size)  # a (1, 1) stand-in when not use_skip
    wf = weights.reshape(weights.size)
    nodes = np.empty(n, dtype=np.float32)  # node ranges, 0 elsewhere
    labels = np.empty(n, dtype=np.int32)  # provisional labels (runs), 0 = no node
    # at most one run per pixel; entries are written when a run starts
    parent = np.empty(n + 1, dtype=np.int32)
    size = np.empty(n + 1, dtype=np.int64)
    parent[0] = 0
    size[0] = 0
    left = np.zeros(w, dtype=np.bool_)  # link of (r, c) to (r, c - 1); left[0]: the seam
    left_up = np.zeros(w, dtype=np.bool_)  # the same for row r - 1
    up = np.zeros(w, dtype=np.bool_)  # link of (r, c) to (r - 1, c)
    n_labels = 0
    for r in range(h):
        row = r * w
        d = nodes[row : row + w]
        if use_skip:
            for c in range(w):
                x = rf[row + c]
                d[c] = x if (x > 0) & ~sf[row + c] else np.float32(0.0)
        else:
            for c in range(w):
                x = rf[row + c]
                d[c] = x if x > 0 else np.float32(0.0)
        ch = angles[0, r, 2]
        sh = angles[0, r, 3]
        if w > 1:
            _link_row(left[1:], d[1:], d[:-1], ch, sh, criterion, param)
        if r > 0:
            above = nodes[row - w : row]
            _link_row(up, d, above, angles[0, r, 0], angles[0, r, 1], criterion, param)
        lab = labels[row : row + w]
        cur = n_labels
        acc = np.int64(0)
        for c in range(w):
            if d[c] > 0:
                if not left[c]:  # a run starts (left[0] is False: the seam comes below)
                    cur += 1
                    parent[cur] = cur
                    acc = 0
                acc += wf[row + c] if use_weights else 1
                size[cur] = acc
                lab[c] = cur
                # merge with the run above, unless the square to the left already joined them
                if up[c] and not (c > 0 and left[c] and up[c - 1] and left_up[c]):
                    _union(parent, cur, labels[row - w + c])
            else:
                lab[c] = 0
        n_labels = cur
        # the 360 deg seam
        if w > 1 and d[0] > 0 and d[w - 1] > 0:
            if _linked(d[w - 1], d[0], ch, sh, criterion, param):  # one column apart
                _union(parent, lab[w - 1], lab[0])
        left, left_up = left_up, left

    # Map Connections; a flat forest first, so that most pairs of one component are recognised by
    # their labels' parents alone
    if steps.shape[0] > 1:
        for lab_ in range(1, n_labels + 1):
            parent[lab_] = parent[parent[lab_]]
    for m in range(1, steps.shape[0]):
        kr = steps[m, 0]
        kc = steps[m, 1]
        if lattice[m]:
            r0 = offsets[m, 0] % kr
            c0 = offsets[m, 1] % kc
            last = c0 + kc * ((w - 1 - c0) // kc)
            rstep = kr
            cstep = kc
        else:
            r0 = 0
            c0 = 0
            last = -1  # the neighbour reading wraps with the modulo
            rstep = 1
            cstep = 1
        for r in range(r0, h, rstep):
            row = r * w
            cv = angles[m, r, 0]
            sv = angles[m, r, 1]
            chm = angles[m, r, 2]
            shm = angles[m, r, 3]
            if r + kr < h:
                below = row + kr * w
                for c in range(c0, w, cstep):
                    d1 = nodes[row + c]
                    if d1 > 0:
                        j = below + c
                        d2 = nodes[j]
                        if d2 > 0 and parent[labels[row + c]] != parent[labels[j]]:
                            if _linked(d1, d2, cv, sv, criterion, param):
                                _union(parent, labels[row + c], labels[j])
            if lattice[m]:
                if last <= c0:  # one lattice column (or none): no horizontal pairs
                    continue
                for c in range(c0, last, cstep):
                    d1 = nodes[row + c]
                    if d1 > 0:
                        j = row + c + kc
                        d2 = nodes[j]
                        if d2 > 0 and parent[labels[row + c]] != parent[labels[j]]:
                            if _linked(d1, d2, chm, shm, criterion, param):
                                _union(parent, labels[row + c], labels[j])
                d1 = nodes[row + last]
                d2 = nodes[row + c0]
                if d1 > 0 and d2 > 0:
                    if _linked(d1, d2, angles[m, r, 4], angles[m, r, 5], criterion, param):
                        _union(parent, labels[row + last], labels[row + c0])
            else:
                shift = kc % w
                if shift == 0:  # every pixel would be its own neighbour
                    continue
                for c in range(w):
                    d1 = nodes[row + c]
                    if d1 > 0:
                        c2 = c + shift
                        j = row + (c2 - w if c2 >= w else c2)
                        d2 = nodes[j]
                        if d2 > 0 and parent[labels[row + c]] != parent[labels[j]]:
                            if _linked(d1, d2, chm, shm, criterion, param):
                                _union(parent, labels[row + c], labels[j])

    # Flatten (ascending: parent[l] <= l), sum the weights of each component at its root, then
    # number the kept roots in ascending order (raster order of their first pixel); parent[l]
    # becomes the final label of l.
    for lab_ in range(1, n_labels + 1):
        root = parent[parent[lab_]]
        parent[lab_] = root
        if root != lab_:
            size[root] += size[lab_]
    k = 0
    for lab_ in range(1, n_labels + 1):
        root = parent[lab_]
        if root == lab_:
            if size[lab_] >= min_size:
                k += 1
                parent[lab_] = k
            else:
                parent[lab_] = 0
        else:
            parent[lab_] = parent[root]
    return labels, parent[: n_labels + 1]


@njit(cache=True)
def connect(
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
) -> np.ndarray:
    """Connected components of the range-image graph, small components dropped, per pixel.

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

    Returns
    -------
    (H, W) int32 labels, 0 = none, 1..K numbered in raster order of first pixel.
    """
    labels, final = _components(
        ranges,
        skip,
        use_skip,
        steps,
        offsets,
        lattice,
        angles,
        criterion,
        param,
        min_size,
        weights,
        use_weights,
    )
    for i in range(labels.size):
        labels[i] = final[labels[i]]
    return labels.reshape(ranges.shape)


@njit(cache=True)
def connect_points(
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
    point_pixel: np.ndarray,
) -> np.ndarray:
    """:func:`connect`, but the label of every point: ``labels[point_pixel]`` (0 where
    ``point_pixel`` is negative: a point without a pixel), without the per-pixel image."""
    labels, final = _components(
        ranges,
        skip,
        use_skip,
        steps,
        offsets,
        lattice,
        angles,
        criterion,
        param,
        min_size,
        weights,
        use_weights,
    )
    out = np.empty(point_pixel.size, dtype=np.int32)
    for j in range(point_pixel.size):
        p = point_pixel[j]
        out[j] = final[labels[p]] if p >= 0 else 0
    return out


#: (elevation bytes, width, sets key, criterion) -> angle_tables; cleared when full
_ANGLES: dict[tuple, np.ndarray] = {}
_NO_ARRAY_2D = np.zeros((1, 1), dtype=np.bool_)
_NO_WEIGHTS = np.zeros((1, 1), dtype=np.int32)


def cached_angles(
    elevation: np.ndarray, width: int, sets: tuple, key: object, criterion: int
) -> np.ndarray:
    """:func:`angle_tables`, computed once per elevation, width and connection sets (``key`` names
    the sets, e.g. the maps and reading; ``sets`` is ``(steps, offsets, lattice)``)."""
    k = (elevation.tobytes(), width, key, criterion)
    out = _ANGLES.get(k)
    if out is None:
        if len(_ANGLES) >= 64:
            _ANGLES.clear()
        out = _ANGLES[k] = angle_tables(elevation, width, *sets, criterion)
    return out


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
    """
    ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    shape = ranges.shape
    elevation = np.ascontiguousarray(elevation, dtype=np.float64)
    if elevation.shape != (shape[0],):
        raise ValueError(f"elevation has shape {elevation.shape}, the image {shape[0]} rows")
    use_skip = skip is not None
    if use_skip:
        skip = np.ascontiguousarray(skip, dtype=np.bool_)
        if skip.shape != shape:
            raise ValueError(f"the mask has shape {skip.shape}, the image {shape}")
    use_weights = weights is not None
    if use_weights:
        weights = np.ascontiguousarray(weights, dtype=np.int32)
        if weights.shape != shape:
            raise ValueError(f"weights have shape {weights.shape}, the image {shape}")
    angles = cached_angles(elevation, shape[1], sets, key, criterion)
    args = (
        ranges,
        skip if use_skip else _NO_ARRAY_2D,
        use_skip,
        *sets,
        angles,
        criterion,
        float(param),
        int(min_size),
        weights if use_weights else _NO_WEIGHTS,
        use_weights,
    )
    if point_pixel is None:
        return connect(*args)
    return connect_points(*args, np.ascontiguousarray(point_pixel, dtype=np.int64))


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
