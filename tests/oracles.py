"""What the tests share: hypothesis strategies for random inputs and brute-force oracles.

The oracles are written plainly, from the definitions, and use no flic code beyond the image
convention (each row's elevation, each column's azimuth): 3D points from the angles, the
connected components of an explicit graph (scipy's labeller), labels renumbered in raster order,
the SemanticKITTI label value spelled out bit by bit. The tests compare flic's kernels with them
on the random inputs drawn here.

Other shared test code: ``conftest.py`` (fixtures: the shared data, the 3-frame sample),
``reference_kernels.py`` (the clusterers' kernels as they were before issue 11's rework, the
reference of the "same labels as before" tests) and ``bagtools.py`` (writes ROS bags and MCAP).
Import from the tests as ``from oracles import ...`` (pytest puts ``tests/`` on ``sys.path``).
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import numpy as np
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from flic_cli.range_image import RangeImage

# ---- strategies: random range images -------------------------------------------------------


@st.composite
def range_images(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray]:
    """Small range images: (ranges (H, W) float32 in m, 0 = empty; elevation (H,) rad, falling).

    Random ranges in 2-12 m, half of them rounded to multiples of 3 m (smooth surfaces, so that
    both connected and separated neighbours occur), up to 40 % empty pixels.
    """
    h = draw(st.integers(1, 7))
    w = draw(st.integers(2, 14))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    ranges = rng.uniform(2.0, 12.0, (h, w))
    # smooth surfaces plus jumps, so that both connected and separated pairs occur
    ranges = np.where(rng.random((h, w)) < 0.5, np.round(ranges / 3) * 3, ranges)
    ranges[rng.random((h, w)) < draw(st.floats(0.0, 0.4))] = 0.0
    elevation = np.sort(rng.uniform(-0.45, 0.05, h))[::-1].copy()
    return ranges.astype(np.float32), elevation


@st.composite
def pixel_weights(draw: st.DrawFn, shape: tuple[int, int]) -> np.ndarray | None:
    """None (count pixels), all ones, or random points per pixel (0..5), as (H, W) int32."""
    kind = draw(st.sampled_from(["none", "ones", "random"]))
    if kind == "none":
        return None
    if kind == "ones":
        return np.ones(shape, np.int32)
    seed = draw(st.integers(0, 2**32 - 1))
    return np.random.default_rng(seed).integers(0, 6, shape).astype(np.int32)


@st.composite
def surface_scenes(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Small range images with surfaces, jumps, holes, near occluders and a mask.

    Returns (ranges (H, W) float32 in m, elevation (H,) rad, mask (H, W) bool, weights (H, W)
    int32 points per pixel in 0..4).
    """
    h = draw(st.integers(1, 8))
    w = draw(st.integers(1, 20))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    # a few flat-ish surfaces at different depths, side by side
    cuts = np.sort(rng.integers(0, w + 1, rng.integers(0, 4)))
    depth = rng.uniform(2.0, 25.0, cuts.size + 1)
    ranges = depth[np.searchsorted(cuts, np.arange(w), side="right")][None, :].repeat(h, 0)
    ranges = ranges * (1.0 + rng.normal(0.0, draw(st.sampled_from([0.0, 0.01, 0.05])), (h, w)))
    occluder = rng.random((h, w)) < draw(st.sampled_from([0.0, 0.15, 0.3]))
    ranges[occluder] *= rng.uniform(0.2, 0.9, occluder.sum())
    ranges[rng.random((h, w)) < draw(st.sampled_from([0.0, 0.3, 0.5]))] = 0.0
    elevation = np.sort(rng.uniform(-0.45, 0.05, h))[::-1].copy()
    mask = rng.random((h, w)) >= draw(st.sampled_from([0.0, 0.2]))
    weights = rng.integers(0, 5, (h, w)).astype(np.int32)
    return ranges.astype(np.float32), elevation, mask, weights


# ---- brute-force oracles -------------------------------------------------------------------


def lab(semantic: int, instance: int = 0) -> int:
    """SemanticKITTI label value: instance in the upper 16 bits, class in the lower 16."""
    return (instance << 16) | semantic


def xyz_of(
    ranges: np.ndarray, elevation: np.ndarray, azimuth_offset: np.ndarray | None = None
) -> np.ndarray:
    """(H, W, 3) float64 points in m from the angles of the image convention.

    ``r cos(el) cos(az), r cos(el) sin(az), r sin(el)`` with each row's elevation and each
    column's azimuth as a native-projection :class:`RangeImage` of that width has them, plus the
    row's ``azimuth_offset`` (radians, None = zeros); no law of cosines, none of flic's point
    code.
    """
    img = RangeImage(ranges.astype(np.float32), elevation, np.zeros(0, np.int64), "native")
    el = img.elevation[:, None]
    az = img.azimuth[None, :]
    if azimuth_offset is not None:
        az = az + np.asarray(azimuth_offset, dtype=np.float64)[:, None]
    r = ranges.astype(np.float64)
    return np.stack(
        [r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el) + 0 * az], -1
    )


def graph_components(n: int, edges: Iterable[tuple[int, int]]) -> np.ndarray:
    """(n,) component id of each of ``n`` nodes of the undirected graph with these edges."""
    pairs = list(edges)
    a = np.array([e[0] for e in pairs] + [0], dtype=np.int64)
    b = np.array([e[1] for e in pairs] + [0], dtype=np.int64)  # (0, 0): no empty matrix
    g = coo_matrix((np.ones(a.size), (a, b)), shape=(n, n))
    return connected_components(g, directed=False)[1]


def canonical(labels: np.ndarray) -> np.ndarray:
    """Renumber labels 1..K in raster order of first appearance (0 stays 0)."""
    flat = labels.reshape(-1)
    out = np.zeros_like(flat)
    mapping: dict[int, int] = {}
    for i, v in enumerate(flat):
        if v > 0:
            out[i] = mapping.setdefault(int(v), len(mapping) + 1)
    return out.reshape(labels.shape)


def image_components(
    shape: tuple[int, int],
    node: np.ndarray,
    edges: Iterable[tuple[int, int]],
    min_size: int = 1,
    weights: np.ndarray | None = None,
) -> np.ndarray:
    """Cluster labels of an image graph, as flic's pixel clusterers number them.

    Parameters
    ----------
    shape : (H, W) of the image.
    node : (H, W) bool, the pixels that are nodes (the others get 0).
    edges : pairs of flat pixel indices ``r * W + c``.
    min_size : smallest component kept, in points (sum of ``weights``).
    weights : (H, W) points per pixel; default 1 each.

    Returns
    -------
    (H, W) int32: components of at least ``min_size`` points numbered 1..K in raster order of
    their first pixel, 0 elsewhere.
    """
    n = shape[0] * shape[1]
    comp = graph_components(n, edges)
    flat_node = node.reshape(-1)
    w = np.ones(n) if weights is None else weights.reshape(-1)
    size = np.bincount(comp[flat_node], weights=w[flat_node], minlength=n)
    out = np.zeros(n, np.int32)
    numbers: dict[int, int] = {}
    for i in np.flatnonzero(flat_node):
        if size[comp[i]] >= min_size:
            out[i] = numbers.setdefault(int(comp[i]), len(numbers) + 1)
    return out.reshape(shape)


def same_partition(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two labelings group the elements identically (labels may differ)."""
    a, b = np.asarray(a), np.asarray(b)
    pairs = np.unique(np.stack([a, b]), axis=1)
    return pairs.shape[1] == np.unique(a).size == np.unique(b).size


def file_tree(root: Path) -> dict[str, bytes]:
    """Every file under ``root``, relative POSIX path -> content ({} if absent, {".": ...} for a
    file), to compare what a writer left with what it should have."""
    if not root.exists():
        return {}
    if root.is_file():
        return {".": root.read_bytes()}
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*") if p.is_file()}


def seen_through_joins(
    labels: np.ndarray,
    raw: np.ndarray,
    node: np.ndarray,
    limit: int,
    depth: float,
    classes: np.ndarray | None = None,
) -> list[tuple[int, int]]:
    """The joins of Bridge's seen-through rule, pixel by pixel as its module docstring says.

    Parameters
    ----------
    labels : (H, W) clusters as the walks left them (every node labelled, > 0).
    raw : (H, W) every range (0 = empty), nodes or not.
    node : (H, W) bool, the nodes.
    limit : the steps of a look (sideways less than a full turn).
    depth : the deepest B may lie behind A.
    classes : (H, W) class of every pixel, or None (any class).

    Returns
    -------
    (B, A) of every cluster B whose outline looks, in each of the four directions, onto A from
    more than half of its outline pixels.
    """
    h, w = labels.shape
    looks: dict[int, list[list[int]]] = {}
    for r in range(h):
        for c in range(w):
            if not node[r, c]:
                continue
            b = int(labels[r, c])
            per_dir = looks.setdefault(b, [[], [], [], []])
            for di, (dr, dc) in enumerate(((0, -1), (0, 1), (-1, 0), (1, 0))):
                steps = min(limit, w - 1) if dr == 0 else limit
                pixels = []
                for k in range(1, steps + 1):
                    if not 0 <= r + k * dr < h:
                        break
                    pixels.append((r + k * dr, (c + k * dc) % w))
                if any(node[p] and labels[p] == b for p in pixels):
                    continue  # no outline pixel: B goes on that way
                first = next((p for p in pixels if 0 < raw[p] <= raw[r, c]), None)
                a = 0
                if first is not None and node[first] and raw[r, c] - raw[first] <= depth:
                    if classes is None or classes[first] == classes[r, c]:
                        a = int(labels[first])
                per_dir[di].append(a)
    joins = []
    for b, per_dir in looks.items():
        if any(not d for d in per_dir):
            continue
        a, count = max(((x, per_dir[0].count(x)) for x in set(per_dir[0])), key=lambda t: t[1])
        if a != 0 and all(2 * d.count(a) > len(d) for d in per_dir):
            joins.append((b, a))
    return joins
