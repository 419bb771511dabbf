"""FLIC and Bogoslavskyi on range images whose rows have their own azimuth offset (Ouster's
``beam_azimuth_angles``): the angle between two pixels' rays is that of their true directions,
checked against brute-force graphs built from the true 3D points."""

from __future__ import annotations

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from flic_cli.methods.bogoslavskyi import Bogoslavskyi, bogoslavskyi_beta, bogoslavskyi_labels
from flic_cli.methods.flic import Flic, flic_labels, flic_labels_scipy
from flic_cli.range_image import from_sensor_image


def true_points(ranges: np.ndarray, elevation: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """(H, W, 3) float64 points from each pixel's own direction: its row's elevation, its column's
    centre azimuth (+pi at column 0, decreasing) plus its row's offset."""
    h, w = ranges.shape
    az = np.pi - (np.arange(w) + 0.5) * (2.0 * np.pi / w)
    az = az[None, :] + offset[:, None]
    el = np.broadcast_to(elevation[:, None], (h, w))
    d = ranges.astype(np.float64)
    return np.stack(
        [d * np.cos(el) * np.cos(az), d * np.cos(el) * np.sin(az), d * np.sin(el)], axis=-1
    )


def pairs(h: int, w: int, maps: list[tuple[int, int]], mc_mode: str):
    """Every pair of pixels the graph tests: the 4-neighbours (wrapping), and each Map
    Connection's pairs (the sub-image of every step-th row and column, or every pixel to its
    step-th neighbour below and to the right)."""
    for kr, kc, lattice in [(1, 1, True)] + [(r, c, mc_mode == "map") for r, c in maps]:
        rows = range(0, h, kr) if lattice else range(h)
        cols = list(range(0, w, kc)) if lattice else list(range(w))
        for r in rows:
            for i, c in enumerate(cols):
                if r + kr < h:
                    yield (r, c), (r + kr, c)
                right = cols[(i + 1) % len(cols)] if lattice else (c + kc) % w
                if right != c:
                    yield (r, c), (r, right)


def components(ranges: np.ndarray, edges: list[tuple[int, int]], min_size: int) -> np.ndarray:
    """(H, W) connected components of the valid pixels, smaller than ``min_size`` pixels
    dropped, numbered 1..K in raster order of their first pixel."""
    h, w = ranges.shape
    n = h * w
    a = [e[0] for e in edges]
    b = [e[1] for e in edges]
    _, comp = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), False)
    valid = ranges.reshape(-1) > 0
    sizes = np.bincount(comp[valid], minlength=n)
    out = np.zeros(n, np.int32)
    names: dict[int, int] = {}
    for i in range(n):
        if valid[i] and sizes[comp[i]] >= min_size:
            out[i] = names.setdefault(int(comp[i]), len(names) + 1)
    return out.reshape(h, w)


@st.composite
def offset_images(draw):
    """Random ranges (smooth patches, jumps, holes), rows sorted downwards, and per-row azimuth
    offsets of up to 3 columns either way (Ouster's are about 1 to 3 columns wide)."""
    h = draw(st.integers(2, 7))
    w = draw(st.integers(3, 16))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    ranges = rng.uniform(2.0, 12.0, (h, w))
    ranges = np.where(rng.random((h, w)) < 0.5, np.round(ranges / 3) * 3, ranges)
    ranges[rng.random((h, w)) < draw(st.floats(0.0, 0.4))] = 0.0
    elevation = np.sort(rng.uniform(-0.45, 0.05, h))[::-1].copy()
    offset = rng.uniform(-3.0, 3.0, h) * (2.0 * np.pi / w)
    return ranges.astype(np.float32), elevation, offset


@settings(max_examples=200, deadline=None)
@given(
    image=offset_images(),
    threshold=st.floats(0.3, 3.0),
    maps=st.lists(st.tuples(st.integers(1, 3), st.integers(1, 4)), max_size=2),
    mc_mode=st.sampled_from(["map", "neighbour"]),
    min_size=st.integers(1, 6),
)
def test_flic_equals_components_of_the_true_3d_distance_graph(
    image, threshold, maps, mc_mode, min_size
):
    ranges, elevation, offset = image
    h, w = ranges.shape
    pts = true_points(ranges, elevation, offset)
    valid = ranges > 0
    edges, dists = [], []
    for (r1, c1), (r2, c2) in pairs(h, w, maps, mc_mode):
        if valid[r1, c1] and valid[r2, c2]:
            d = float(np.linalg.norm(pts[r1, c1] - pts[r2, c2]))
            dists.append(d)
            if d < threshold:
                edges.append((r1 * w + c1, r2 * w + c2))
    assume(all(abs(d - threshold) > 1e-4 for d in dists))  # float32 ranges: no near-ties
    expected = components(ranges, edges, min_size)
    maps = tuple(maps)
    got = flic_labels(ranges, elevation, threshold, min_size, maps, mc_mode, azimuth_offset=offset)
    np.testing.assert_array_equal(got, expected)
    ref = flic_labels_scipy(
        ranges, elevation, threshold, min_size, maps, mc_mode, azimuth_offset=offset
    )
    np.testing.assert_array_equal(ref, expected)
    # the method reads the offsets from the image (one point per pixel: its labels per point)
    img = from_sensor_image(ranges, elevation, offset)
    for backend in ("numba", "scipy"):
        method = Flic(threshold, min_size, maps, mc_mode, backend)
        per_point = method.segment(img, img.to_points()[img.point_pixel], None)
        np.testing.assert_array_equal(per_point, expected.reshape(-1)[img.point_pixel])


@settings(max_examples=200, deadline=None)
@given(image=offset_images(), angle=st.floats(2.0, 60.0), min_size=st.integers(1, 6))
def test_bogoslavskyi_equals_components_of_the_true_atan2_graph(image, angle, min_size):
    ranges, elevation, offset = image
    h, w = ranges.shape
    theta = np.radians(angle)
    pts = true_points(ranges, elevation, offset)
    edges, betas = [], []
    for (r1, c1), (r2, c2) in pairs(h, w, [], "map"):
        if ranges[r1, c1] > 0 and ranges[r2, c2] > 0:
            u, v = pts[r1, c1], pts[r2, c2]
            alpha = np.arccos(np.clip(u @ v / np.linalg.norm(u) / np.linalg.norm(v), -1, 1))
            beta = float(bogoslavskyi_beta(ranges[r1, c1], ranges[r2, c2], alpha))
            betas.append(beta)
            if beta > theta:
                edges.append((r1 * w + c1, r2 * w + c2))
    assume(all(abs(b - theta) > 1e-5 for b in betas))
    expected = components(ranges, edges, min_size)
    got = bogoslavskyi_labels(ranges, elevation, angle, min_size, azimuth_offset=offset)
    np.testing.assert_array_equal(got, expected)
    img = from_sensor_image(ranges, elevation, offset)
    per_point = Bogoslavskyi(angle, min_size).segment(img, img.to_points()[img.point_pixel], None)
    np.testing.assert_array_equal(per_point, expected.reshape(-1)[img.point_pixel])


def test_an_offset_separates_vertical_neighbours():
    # Two rows 0.2 deg apart at 1 m: 3.5 mm apart without offsets, so every column links its two
    # pixels; with the lower row turned by 0.5 rad they are 0.49 m apart, more than 0.3 m, and
    # (8 columns, 45 deg) no row links its own pixels: 16 clusters.
    ranges = np.ones((2, 8), np.float32)
    elevation = np.radians([0.0, -0.2])
    assert flic_labels(ranges, elevation, 0.3, 1).max() == 8
    offset = np.array([0.0, 0.5])
    assert flic_labels(ranges, elevation, 0.3, 1, azimuth_offset=offset).max() == 16
    assert flic_labels_scipy(ranges, elevation, 0.3, 1, azimuth_offset=offset).max() == 16
    # the same offset on both rows turns the whole image: the links are those without offsets
    both = np.array([0.5, 0.5])
    np.testing.assert_array_equal(
        flic_labels(ranges, elevation, 0.3, 1, azimuth_offset=both),
        flic_labels(ranges, elevation, 0.3, 1),
    )
