"""Numba kernel: connected components of the range-image graph of FLIC and Bogoslavskyi.

Why not ``scipy.ndimage.label``: FLIC's and Bogoslavskyi's connectivity is decided per *edge* (a
distance or angle test between two measurements), not per pixel. ``ndimage.label`` needs the
paper's super-sized image (4x the pixels, then extra passes for the 360 deg seam and the Map
Connections) and ``scipy.sparse.csgraph.connected_components`` needs the edge list built as a
sparse matrix first; both cost more than the clustering itself. The tests check this kernel against
``connected_components`` of a brute-force graph built from the 3D coordinates, and against the
previous pixel-by-pixel union-find (``tests/reference_kernels.py``): same labels.

How it works: two-pass labelling over *runs* (the classic scheme for binary images, with the pixel
test replaced by an edge test), written so that the per-pixel work has no branches:

1. Row by row, loops that LLVM vectorises compute the node ranges (the range where the pixel takes
   part, 0 elsewhere: no measurement, or left out e.g. as ground), and whether each pixel is linked
   to its left neighbour and to the one above. These flags are packed into 64-bit words.
2. A *run* is a maximal stretch of nodes, each linked to its left neighbour. Word operations give
   the runs' first and last pixels, and the pixels whose link upwards must merge two labels: the
   first pixel of a run takes the label above it when linked upwards (else a new label), and a
   later pixel's link upwards needs a merge only where the square to its left (left, up-left and
   up-left to up linked) has not joined the same two runs already. So most runs cost no merge,
   and only set bits are visited (``trailing_zeros``). A run's label is written 8 pixels at a
   time; a pass clears the pixels that are not nodes.
3. The 360 deg seam merges the first and last pixel of each row. A Map Connection can only change
   anything between pixels in different components of the direct connections: each pair row's
   flag "different components" is computed over the whole row (vectorised), packed, masked to the
   connection's columns, and only the flagged pairs are tested and merged.
4. One pass over the labels (few: runs share them) flattens the union-find forest, sums the weights
   of each component and numbers the kept components 1..K in order of their smallest label, i.e.
   of their first pixel in raster order. Then the labels of the pixels or of the points.

Union by the smaller label keeps ``parent[l] <= l`` (labels are created in raster order), so one
ascending pass flattens the forest and a component's root is the label of its first pixel. The
link tests are the ones the labels were defined with, operation for operation (float32 squares,
float64 cross term), so that no edge changes.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from flic_cli.bitwords import pack, trailing_zeros

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
            big = d1 if d1 > d2 else d2
            small = d2 if d1 > d2 else d1
            den = big - small * cos_a
            out[c] = (d1 > 0) & (d2 > 0) & ((den <= 0.0) | (small * sin_a > param * den))


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
    above, ``above[c]``; one branch-free pass (see :func:`_link_row`)."""
    if criterion == DISTANCE:
        for c in range(1, d.size):
            d1 = d[c]
            d2 = d[c - 1]
            d3 = above[c]
            sq = d1 * d1
            left[c] = (d1 > 0) & (d2 > 0) & (sq + d2 * d2 - 2.0 * ch * d1 * d2 < param)
            up[c] = (d1 > 0) & (d3 > 0) & (sq + d3 * d3 - 2.0 * cv * d1 * d3 < param)
    else:
        for c in range(1, d.size):
            d1 = d[c]
            d2 = d[c - 1]
            d3 = above[c]
            big = d1 if d1 > d2 else d2
            small = d2 if d1 > d2 else d1
            den = big - small * ch
            left[c] = (d1 > 0) & (d2 > 0) & ((den <= 0.0) | (small * sh > param * den))
            big = d1 if d1 > d3 else d3
            small = d3 if d1 > d3 else d1
            den = big - small * cv
            up[c] = (d1 > 0) & (d3 > 0) & ((den <= 0.0) | (small * sv > param * den))
    d1 = d[0]
    d3 = above[0]
    up[0] = (d1 > 0) & (d3 > 0) & _linked(d1, d3, cv, sv, criterion, param)


@njit(cache=True)
def _differ(flags: np.ndarray, a: np.ndarray, b: np.ndarray) -> None:
    """``flags[c]``: ``a[c]`` and ``b[c]`` are nodes (label != 0) of different components;
    branch-free, so that LLVM vectorises it."""
    for c in range(a.size):
        x = a[c]
        y = b[c]
        flags[c] = (x != y) & (x != 0) & (y != 0)


@njit(cache=True)
def _join_flagged(
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
    """Merge the linked pairs (row + c, partner + c) for the set bits c of ``words & mask``; a
    partner column past ``wrap`` is taken ``w`` columns back (the 360 deg seam)."""
    one = np.uint64(1)
    for k in range(words.size):
        bits = words[k] & mask[k]
        while bits:
            c = 64 * k + np.int64(trailing_zeros(bits))
            bits &= bits - one
            i = row + c
            j = partner + c - (w if c >= wrap else 0)
            if _linked(nodes[i], nodes[j], cos_a, sin_a, criterion, param):
                _union(parent, comp[i], comp[j])


@njit(cache=True)
def _lattice_mask(mask: np.ndarray, first: int, step: int, count: int) -> None:
    """Set bits ``first + q step``, q < count, of the words ``mask`` (cleared first)."""
    mask[:] = 0
    for q in range(count):
        c = first + q * step
        mask[c >> 6] |= np.uint64(1) << np.uint64(c & 63)


@njit(cache=True)
def _run_buffers(n: int, w: int) -> tuple:
    """The arrays of :func:`_label_row`: labels (n + 8, see there), parent and size (one per
    possible label), the row's flags as bytes (node, left, up) and as words (node, left, left of
    the row above, up), and the row's runs and weights."""
    labels = np.empty(n + 8, dtype=np.uint32)
    parent = np.empty(n + 1, dtype=np.uint32)  # at most one new label per pixel
    size = np.empty(n + 1, dtype=np.int64)
    parent[0] = 0
    size[0] = 0
    nw = (w + 63) // 64
    pad = 64 * nw + 8
    node = np.zeros(pad, dtype=np.uint8)
    left = np.zeros(pad, dtype=np.uint8)
    up = np.zeros(pad, dtype=np.uint8)
    node_w = np.zeros(nw + 1, dtype=np.uint64)  # one zero word after the last
    left_w = np.zeros(nw + 1, dtype=np.uint64)
    left_up_w = np.zeros(nw + 1, dtype=np.uint64)
    up_w = np.zeros(nw + 1, dtype=np.uint64)
    starts = np.empty(w + 1, dtype=np.uint64)
    ends = np.empty(w + 1, dtype=np.uint64)
    acc = np.zeros(w + 1, dtype=np.int64)
    return (
        labels,
        parent,
        size,
        node,
        left,
        up,
        node_w,
        left_w,
        left_up_w,
        up_w,
        starts,
        ends,
        acc,
    )


@njit(cache=True, inline="always")
def _label_row(
    r: int,
    w: int,
    n_labels: np.uint64,
    d: np.ndarray,
    node: np.ndarray,
    left: np.ndarray,
    up: np.ndarray,
    node_w: np.ndarray,
    left_w: np.ndarray,
    left_up_w: np.ndarray,
    up_w: np.ndarray,
    starts: np.ndarray,
    ends: np.ndarray,
    acc: np.ndarray,
    labels: np.ndarray,
    parent: np.ndarray,
    size: np.ndarray,
    wf: np.ndarray,
    use_weights: bool,
) -> np.uint64:
    """Label the nodes of row ``r`` by runs; returns the number of labels so far.

    ``d``: the row's node ranges (0 = no node); ``node[c]``: (r, c) is a node; ``left[c]``: it is
    linked to (r, c - 1) (``left[0] = 0``: the seam is the caller's); ``up[c]``: linked to
    (r - 1, c) (0 in row 0). ``node_w``, ``left_w``, ``up_w``: the same packed in words (written
    here); ``left_up_w``: ``left_w`` of row r - 1 (the caller swaps the two after each row).

    A run (maximal stretch of left-linked nodes) whose first pixel is linked upwards takes the
    label above it, else a new label (parent = itself); ``size`` sums the weights per label. A
    later upward link merges the two labels unless the square to its left (left, up-left, and
    up-left to up) has joined them already. ``labels[row*w + c]`` gets the label of every node, 0
    elsewhere (``labels`` has 8 entries of slack after the last pixel). ``wf``: points per pixel
    when ``use_weights``, else every node counts 1.
    """
    nw = node_w.size - 1
    one = np.uint64(1)
    top = np.uint64(63)
    eight = np.uint64(8)
    row = r * w
    rowu = np.uint64(row)
    wu = np.uint64(w)
    pack(node[: 64 * nw], node_w[:nw])
    pack(left[: 64 * nw], left_w[:nw])
    pack(up[: 64 * nw], up_w[:nw])
    # the runs' first and last pixels, word by word; only set bits are visited
    ns = 0
    ne = 0
    for k in range(nw):
        base = np.uint64(64 * k)
        nk = node_w[k]
        lk = left_w[k]
        bits = nk & ~lk
        while bits:
            starts[ns] = base + trailing_zeros(bits)
            ns += 1
            bits &= bits - one
        bits = nk & ~((lk >> one) | (left_w[k + 1] << top))
        while bits:
            ends[ne] = base + trailing_zeros(bits) + one
            ne += 1
            bits &= bits - one
    if use_weights:
        total = np.int64(0)
        for c in range(w):
            acc[c] = total
            total += wf[row + c]
        acc[w] = total
    cur = n_labels
    above_row = rowu - wu if r > 0 else rowu
    for q in range(ns):
        a = starts[q]
        b = ends[q]
        if up[a]:  # the run continues the run above its first pixel: its label
            lab_q = np.uint64(labels[above_row + a])
        else:
            cur += one
            parent[cur] = cur
            size[cur] = 0
            lab_q = cur
        size[lab_q] += acc[b] - acc[a] if use_weights else np.int64(b - a)
        p = rowu + a
        p_end = rowu + b
        while True:  # 8 at a time (most runs are shorter): one predictable branch
            labels[p] = lab_q
            labels[p + one] = lab_q
            labels[p + np.uint64(2)] = lab_q
            labels[p + np.uint64(3)] = lab_q
            labels[p + np.uint64(4)] = lab_q
            labels[p + np.uint64(5)] = lab_q
            labels[p + np.uint64(6)] = lab_q
            labels[p + np.uint64(7)] = lab_q
            p += eight
            if p >= p_end:
                break
    lab = labels[row : row + w]
    for c in range(w):
        lab[c] = lab[c] if d[c] > 0 else 0
    if r > 0:
        carry = np.uint64(0)
        for k in range(nw):
            uk = up_w[k]
            bits = uk & left_w[k] & ~(((uk << one) | carry) & left_up_w[k])
            carry = uk >> top
            base = rowu + np.uint64(64 * k)
            while bits:
                p = base + trailing_zeros(bits)
                _union(parent, labels[p], labels[p - wu])
                bits &= bits - one
    return cur


@njit(cache=True, inline="always")
def _attach(labels: np.ndarray, size: np.ndarray, attached: np.ndarray) -> None:
    """Give every held pixel the provisional label of the pixel standing on it and add its
    points to that label's size (``attached``: (K, 3) held pixel, target pixel or -1, points;
    see :attr:`flic_cli.range_image.RangeImage.attached`). A held pixel is no node, so it links
    nothing; a target that is no node gives it none."""
    for k in range(attached.shape[0]):
        t = attached[k, 1]
        if t < 0:
            continue
        lab = labels[t]
        if lab > 0:
            labels[attached[k, 0]] = lab
            size[lab] += attached[k, 2]


@njit(cache=True)
def _number(parent: np.ndarray, size: np.ndarray, n_labels: int, min_size: int) -> np.ndarray:
    """Final label of every provisional label (``parent[:n_labels + 1]``, modified).

    Flattens the forest (ascending: ``parent[l] <= l``), sums the weights of each component at
    its root, then numbers the kept roots in ascending order (raster order of their first pixel).
    """
    for lab in range(1, n_labels + 1):
        root = parent[parent[lab]]
        parent[lab] = root
        if root != lab:
            size[root] += size[lab]
    k = 0
    for lab in range(1, n_labels + 1):
        root = parent[lab]
        if root == lab:
            if size[lab] >= min_size:
                k += 1
                parent[lab] = k
            else:
                parent[lab] = 0
        else:
            parent[lab] = parent[root]
    return parent[: n_labels + 1]


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
    attached: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Provisional label of every pixel (0 = no node) and the final label of each provisional
    label (0 = dropped); parameters as :func:`connect`."""
    h, w = ranges.shape
    n = h * w
    rf = ranges.reshape(n)
    sf = skip.reshape(skip.size)  # a (1, 1) stand-in when not use_skip
    wf = weights.reshape(weights.size)
    nodes = np.empty(n, dtype=np.float32)  # node ranges, 0 elsewhere
    (
        labels, parent, size, node, left, up, node_w, left_w, left_up_w, up_w, starts, ends, acc
    ) = _run_buffers(n, w)  # fmt: skip
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
        n_labels = _label_row(
            r, w, n_labels, d, node, left, up, node_w, left_w, left_up_w, up_w, starts, ends, acc,
            labels, parent, size, wf, use_weights,
        )  # fmt: skip
        left_w, left_up_w = left_up_w, left_w
        # the 360 deg seam
        if w > 1 and d[0] > 0 and d[w - 1] > 0:
            if _linked(d[w - 1], d[0], ch, sh, criterion, param):  # one column apart
                _union(parent, labels[row + w - 1], labels[row])

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
    for m in range(1, steps.shape[0]):
        kr = steps[m, 0]
        kc = steps[m, 1]
        if lattice[m]:
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
                if r + kr < h:
                    below = row + kr * w
                    _differ(flags[:w], comp[row : row + w], comp[below : below + w])
                    pack(flags[: 64 * nw], flag_w)
                    _join_flagged(
                        flag_w, mask_v, comp, nodes, parent, row, below, w, w,
                        angles[m, r, 0], angles[m, r, 1], criterion, param,
                    )  # fmt: skip
                if cols > 1:
                    # pairs (c, c + kc) of lattice columns c < last
                    i0 = row + c0
                    i1 = row + last - kc + 1
                    _differ(flags[c0 : last - kc + 1], comp[i0:i1], comp[i0 + kc : i1 + kc])
                    pack(flags[: 64 * nw], flag_w)
                    _join_flagged(
                        flag_w, mask_h, comp, nodes, parent, row, row + kc, w, w,
                        angles[m, r, 2], angles[m, r, 3], criterion, param,
                    )  # fmt: skip
                    # from the last lattice column across the seam to the first
                    i = row + last
                    j = row + c0
                    if comp[i] != comp[j] and comp[i] != 0 and comp[j] != 0:
                        if _linked(nodes[i], nodes[j], angles[m, r, 4], angles[m, r, 5],
                                   criterion, param):  # fmt: skip
                            _union(parent, comp[i], comp[j])
        else:
            shift = kc % w
            _lattice_mask(mask_v, 0, 1, w)
            for r in range(h):
                row = r * w
                if r + kr < h:
                    below = row + kr * w
                    _differ(flags[:w], comp[row : row + w], comp[below : below + w])
                    pack(flags[: 64 * nw], flag_w)
                    _join_flagged(
                        flag_w, mask_v, comp, nodes, parent, row, below, w, w,
                        angles[m, r, 0], angles[m, r, 1], criterion, param,
                    )  # fmt: skip
                if shift:  # (else every pixel would be its own neighbour)
                    rest = w - shift
                    _differ(flags[:rest], comp[row : row + rest], comp[row + shift : row + w])
                    _differ(flags[rest:w], comp[row + rest : row + w], comp[row : row + shift])
                    pack(flags[: 64 * nw], flag_w)
                    _join_flagged(
                        flag_w, mask_v, comp, nodes, parent, row, row + shift, rest, w,
                        angles[m, r, 2], angles[m, r, 3], criterion, param,
                    )  # fmt: skip

    _attach(labels, size, attached)
    return labels[:n], _number(parent, size, nl, min_size)


@njit(cache=True, inline="always")
def pixel_output(labels: np.ndarray, final: np.ndarray) -> np.ndarray:
    """(N,) int32 final label of every pixel (``labels``: uint32 provisional ones, overwritten)."""
    for i in range(labels.size):
        labels[i] = final[labels[i]]
    return labels.view(np.int32)


@njit(cache=True, inline="always")
def point_output(labels: np.ndarray, final: np.ndarray, point_pixel: np.ndarray) -> np.ndarray:
    """(N_points,) int32 final label of every point: that of its pixel, 0 where ``point_pixel``
    is negative (a point without a pixel)."""
    out = np.empty(point_pixel.size, dtype=np.int32)
    pix = point_pixel.view(np.uint64)  # -1 becomes the largest value (unsigned: no index test)
    n = np.uint64(labels.size)
    for j in range(pix.size):
        p = pix[j]
        out[j] = final[labels[p]] if p < n else 0
    return out


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
    attached: np.ndarray,
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
    attached : (K, 3) int64, held pixels (left out by ``skip``) that take the component of the
        pixel standing on them, with their points (:attr:`flic_cli.range_image.RangeImage.
        attached`; (0, 3) for none).

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
        attached,
    )
    return pixel_output(labels, final).reshape(ranges.shape)


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
    attached: np.ndarray,
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
        attached,
    )
    return point_output(labels, final, point_pixel)


#: (elevation bytes, width, sets key, criterion) -> angle_tables; cleared when full
_ANGLES: dict[tuple, np.ndarray] = {}
_NO_ARRAY_2D = np.zeros((1, 1), dtype=np.bool_)
_NO_WEIGHTS = np.zeros((1, 1), dtype=np.int32)
_NO_ATTACHED = np.zeros((0, 3), dtype=np.int64)


def attached_input(attached: np.ndarray | None) -> np.ndarray:
    """The kernels' ``attached`` argument: (K, 3) contiguous int64, (0, 3) for None."""
    if attached is None:
        return _NO_ATTACHED
    return np.ascontiguousarray(attached, dtype=np.int64).reshape(-1, 3)


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


def kernel_inputs(
    ranges: np.ndarray,
    elevation: np.ndarray,
    skip: np.ndarray | None,
    weights: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool, np.ndarray, bool]:
    """The kernels' arguments: contiguous float32 ranges, float64 elevation, the mask of pixels
    left out and the weights as contiguous arrays (a small stand-in when None) with the flags
    ``use_skip`` and ``use_weights``; shapes are checked."""
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
    return (
        ranges,
        elevation,
        skip if use_skip else _NO_ARRAY_2D,
        use_skip,
        weights if use_weights else _NO_WEIGHTS,
        use_weights,
    )


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
    """
    ranges, elevation, skip, use_skip, weights, use_weights = kernel_inputs(
        ranges, elevation, skip, weights
    )
    angles = cached_angles(elevation, ranges.shape[1], sets, key, criterion)
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
    return connect_points(*args, np.ascontiguousarray(point_pixel, dtype=np.int64))
