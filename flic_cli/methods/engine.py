"""The connected-component engine of the range-image clusterers: run-based labelling with
union-find, numbering and the held cells' attachment (numba).

The graphs of FLIC and Bogoslavskyi (:mod:`flic_cli.methods.connections`) and of Bridge
(:mod:`flic_cli.methods.bridge`) decide their edges with the tests of
:mod:`flic_cli.methods.criteria`; this module labels their components. Why not
``scipy.ndimage.label``: the connectivity is decided per *edge* (a distance or angle test
between two measurements), not per pixel. ``ndimage.label`` needs the paper's super-sized image
(4x the pixels, then extra passes for the 360 deg seam and the Map Connections) and
``scipy.sparse.csgraph.connected_components`` needs the edge list built as a sparse matrix
first; both cost more than the clustering itself. The tests check the kernels against
``connected_components`` of a brute-force graph built from the 3D coordinates, and against the
previous pixel-by-pixel union-find (``tests/reference_kernels.py``): same labels.

How a graph uses it, row by row (two-pass labelling over *runs*, the classic scheme for binary
images with the pixel test replaced by an edge test, written so that the per-pixel work has no
branches):

1. The caller computes, in loops that LLVM vectorises, the node ranges of the row (the range
   where the pixel takes part, 0 elsewhere: no measurement, or left out e.g. as ground) and
   whether each pixel is linked to its left neighbour and to the one above (the buffers of
   :func:`run_buffers`).
2. :func:`label_row`: a *run* is a maximal stretch of nodes, each linked to its left neighbour.
   Word operations give the runs' first and last pixels, and the pixels whose link upwards must
   merge two labels: the first pixel of a run takes the label above it when linked upwards
   (else a new label), and a later pixel's link upwards needs a merge only where the square to
   its left (left, up-left and up-left to up linked) has not joined the same two runs already.
   So most runs cost no merge, and only set bits are visited (``trailing_zeros``). A run's
   label is written 8 pixels at a time; a pass clears the pixels that are not nodes.
3. Any further edge (the seam, Map Connections, Bridge's walks) merges two labels with
   :func:`union`.
4. :func:`attach` gives the held cells the label of the cell standing on them; :func:`number`
   flattens the union-find forest in one pass over the labels (few: runs share them), sums the
   weights of each component and numbers the kept components 1..K in order of their smallest
   label, i.e. of their first pixel in raster order; :func:`pixel_output` or
   :func:`point_output` give the labels of the pixels or of the points.

Union by the smaller label keeps ``parent[l] <= l`` (labels are created in raster order), so one
ascending pass flattens the forest and a component's root is the label of its first pixel.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from flic_cli.bitwords import pack, trailing_zeros

#: The engine's interface: the graphs (:mod:`flic_cli.methods.connections`,
#: :mod:`flic_cli.methods.bridge`) use these names only.
__all__ = [
    "attach",
    "attached_input",
    "find",
    "kernel_inputs",
    "label_row",
    "number",
    "pixel_output",
    "point_output",
    "run_buffers",
    "union",
]


@njit(cache=True, inline="always")
def find(parent: np.ndarray, i: int) -> int:
    """Root of ``i`` (path halving)."""
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, inline="always")
def union(parent: np.ndarray, a: int, b: int) -> None:
    """Merge the sets of ``a`` and ``b``: the larger root hangs under the smaller one."""
    if parent[a] == parent[b]:
        return
    ra = find(parent, a)
    rb = find(parent, b)
    if ra < rb:
        parent[rb] = ra
    elif rb < ra:
        parent[ra] = rb


@njit(cache=True)
def run_buffers(n: int, w: int) -> tuple:
    """The arrays of :func:`label_row`: labels (n + 8, see there), parent and size (one per
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
def label_row(
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
                union(parent, labels[p], labels[p - wu])
                bits &= bits - one
    return cur


@njit(cache=True, inline="always")
def attach(labels: np.ndarray, size: np.ndarray, attached: np.ndarray) -> None:
    """Give every held pixel the provisional label of the pixel standing on it and add its
    points to that label's size (``attached``: (K, 3) held pixel, target pixel or -1, points;
    see :attr:`flic_cli.ground.base.Ground.attached`). A held pixel is no node, so it links
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
def number(parent: np.ndarray, size: np.ndarray, n_labels: int, min_size: int) -> np.ndarray:
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


_NO_ARRAY_2D = np.zeros((1, 1), dtype=np.bool_)

_NO_WEIGHTS = np.zeros((1, 1), dtype=np.int32)

_NO_ATTACHED = np.zeros((0, 3), dtype=np.int64)


def attached_input(attached: np.ndarray | None) -> np.ndarray:
    """The kernels' ``attached`` argument: (K, 3) contiguous int64, (0, 3) for None."""
    if attached is None:
        return _NO_ATTACHED
    return np.ascontiguousarray(attached, dtype=np.int64).reshape(-1, 3)


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
