"""Ground extraction on the synthetic street, whose labels say what is road and what is a car."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from flic_cli.ground import bogoslavskyi_ground, paper_ground
from flic_cli.ground.bogoslavskyi import (
    _repair_and_legs,
    _repair_depth,
    _row_trig,
    _smooth_columns,
    _smooth_grow_shift,
    savgol_kernel,
)
from flic_cli.ground.paper import paper_tables
from flic_cli.io import open_dataset
from flic_cli.projection import project_points
from flic_cli.range_image import RangeImage


def _frames(sample):
    ds = open_dataset(sample.kitti_root)
    for ref in ds.refs():
        frame = ds.load(ref)
        yield frame, project_points(frame.points)


def _shares(frame, image, ground, max_dist):
    on_ground = ground.reshape(-1)[image.point_pixel]
    sem = frame.labels & 0xFFFF
    x, y, z = frame.points.T
    rho = np.hypot(x, y)
    above_line = z > -1.73 + np.tan(np.radians(10.0)) * rho + 0.05
    roofs = np.isin(sem, [10, 252]) & (z > -0.5) & (rho < max_dist) & above_line
    assert roofs.sum() > 300  # the scene has car roofs and hoods in view
    return on_ground[sem == 40].mean(), on_ground[roofs].mean()


def test_paper_ground_removes_the_road_and_keeps_car_roofs(small_sample):
    # The paper keeps horizontal surfaces above the line rising at 10 deg from the wheel (a roof
    # 0.2 m below the sensor up to ~8.7 m away); beyond the line the paper calls them ground.
    for frame, image in _frames(small_sample):
        road, roofs = _shares(frame, image, paper_ground(image), max_dist=8.0)
        assert road > 0.9
        assert roofs < 0.02


def test_bogoslavskyi_ground_removes_the_road_and_keeps_car_roofs(small_sample):
    # Their remover, as their code runs it, leaves some road: the label image moves down one row
    # (the empty "dilation" kernel), so the top row of every grown region stays.
    for frame, image in _frames(small_sample):
        road, roofs = _shares(frame, image, bogoslavskyi_ground(image), max_dist=15.0)
        assert road > 0.85
        assert roofs < 0.02


def test_paper_ground_height_line_keeps_a_horizontal_surface_above_it():
    # A flat plane seen by 8 beams: at the road height (-1.73 m) it is ground; raised to -0.3 m
    # (a car roof) it is above the 10 deg line from the wheel for the near cells and stays.
    elevation = np.radians(np.linspace(-8, -22, 8))
    for height, expect_ground in ((-1.73, True), (-0.3, False)):
        ranges = (height / np.sin(elevation)).astype(np.float32)[:, None].repeat(16, 1)
        image = RangeImage(ranges, elevation, np.arange(ranges.size), "native")
        ground = paper_ground(image)
        assert ground.all() == expect_ground and ground.any() == expect_ground


def test_paper_ground_keeps_a_wall():
    elevation = np.radians(np.linspace(-2, -20, 10))
    ranges = (5.0 / np.cos(elevation)).astype(np.float32)[:, None].repeat(8, 1)  # wall 5 m away
    image = RangeImage(ranges, elevation, np.arange(ranges.size), "native")
    assert not paper_ground(image).any()


def test_paper_tables_accept_the_depression_angle_band():
    # tan(beta) for a horizontal surface equals tan of the upper beam's depression angle
    elevation = np.radians([-10.0, -11.0])
    sin_a, cos_a, tan_lo, tan_hi = paper_tables(elevation, 10.0)
    d1 = 1.73 / np.sin(np.radians(10.0))
    d2 = 1.73 / np.sin(np.radians(11.0))
    tan_beta = d2 * sin_a[1] / (d1 - d2 * cos_a[1])
    assert np.degrees(np.arctan(tan_beta)) == pytest.approx(10.0, abs=1e-6)
    assert tan_lo[1] <= tan_beta <= tan_hi[1]
    assert np.degrees(np.arctan(tan_lo[1])) == pytest.approx(0.0, abs=1e-9)
    assert np.degrees(np.arctan(tan_hi[1])) == pytest.approx(20.0)


def test_empty_pixels_are_never_ground():
    image = RangeImage(
        np.zeros((4, 8), np.float32),
        np.radians([-5, -6, -7, -8.0]),
        np.zeros(0, np.int64),
        "native",
    )
    assert not paper_ground(image).any()
    assert not bogoslavskyi_ground(image).any()


@pytest.mark.parametrize(
    ("window", "tabulated"),
    [
        (5, np.array([-3, 12, 17, 12, -3]) / 35),
        (7, np.array([-2, 3, 6, 7, 6, 3, -2]) / 21),
        (9, np.array([-21, 14, 39, 54, 59, 54, 39, 14, -21]) / 231),
        (11, np.array([-36, 9, 44, 69, 84, 89, 84, 69, 44, 9, -36]) / 429),
    ],
)
def test_savgol_kernel_is_the_one_tabulated_in_their_code(window, tabulated):
    assert np.allclose(savgol_kernel(window), tabulated, atol=1e-7)


def test_bogoslavskyi_repair_in_paints_a_gap_from_pairs_within_1_m():
    # One column: 10, 0, 10.5, 0, 0, 0, 0, 0, 20 (metres). Row 1: the pairs (above, below) within
    # 1 m are (10, 10.5) only -> 10.25. Rows 3..7 see 10.5 above and, from row 4 on, 20 below:
    # too far apart; row 3 also sees the in-painted 10.25 above, still nothing close below.
    col = np.array([10, 0, 10.5, 0, 0, 0, 0, 0, 20], dtype=np.float32)[:, None]
    out = _repair_depth(col, 5, 1.0)[:, 0]
    assert out[1] == pytest.approx(10.25)
    assert np.array_equal(out[3:8], np.zeros(5, np.float32))
    # in place, top down: row 2 of 10, 0, 0, 10.4 takes row 1's in-painted value into its pairs
    col = np.array([10, 0, 0, 10.4], dtype=np.float32)[:, None]
    out = _repair_depth(col, 5, 1.0)[:, 0]
    assert out[1] == pytest.approx(10.2)  # pairs (10, 10.4)
    assert out[2] == pytest.approx((10.2 + 10.4 + 10 + 10.4) / 4)  # (10.2, 10.4), (10, 10.4)


def test_bogoslavskyi_labels_move_down_one_row():
    # A flat road seen by 12 beams: the growth labels every pixel, and their empty "dilation"
    # kernel moves the labels down one row, so the top row is never ground and every other is.
    elevation = np.radians(np.linspace(-6, -20, 12))
    ranges = (1.73 / np.sin(-elevation)).astype(np.float32)[:, None].repeat(32, 1)
    image = RangeImage(ranges, elevation, np.arange(ranges.size), "native")
    ground = bogoslavskyi_ground(image)
    assert not ground[0].any()
    assert ground[1:].all()


def _growth_reference(ranges, depth, smooth, threshold, start):
    """Their growth as the module docstring states it (steps 4 and 5), plain Python, a queue."""
    from collections import deque

    h, w = depth.shape
    label = np.zeros((h, w), dtype=bool)
    for c in range(w):
        r = h - 1
        while r > 0 and depth[r, c] < 0.001:
            r -= 1
        if label[r, c] or smooth[r, c] > start:
            continue
        label[r, c] = True
        queue = deque([(r, c)])
        while queue:
            pr, pc = queue.popleft()
            if depth[pr, pc] < 0.001:
                continue
            for nr, nc in ((pr - 1, pc), (pr + 1, pc), (pr, (pc - 1) % w), (pr, (pc + 1) % w)):
                if 0 <= nr < h and not label[nr, nc]:
                    if abs(smooth[pr, pc] - smooth[nr, nc]) < threshold:
                        label[nr, nc] = True
                        queue.append((nr, nc))
    ground = np.zeros((h, w), dtype=bool)
    ground[1:] = label[:-1] & (ranges[1:] > 0)
    return ground


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    shape=st.tuples(st.integers(2, 16), st.integers(1, 24)),
    empty=st.floats(0.0, 0.6),
    angle_deg=st.floats(1.0, 30.0),
)
def test_bogoslavskyi_growth_equals_the_rule_with_a_queue(seed, shape, empty, angle_deg):
    # Random scenes: a road with steps and walls, random holes. The depth-first stack of the
    # kernel and a breadth-first queue must label the same pixels (the labelled set does not
    # depend on the order), given the same smoothed angles.
    rng = np.random.default_rng(seed)
    h, w = shape
    elevation = np.radians(np.linspace(2.0, -24.0, h))
    road = 1.73 / np.maximum(np.sin(-elevation), 0.05)
    ranges = (road[:, None] * rng.uniform(0.3, 1.2, (h, w))).astype(np.float32)
    ranges[rng.random((h, w)) < empty] = 0
    sin_p, cos_p = _row_trig(elevation)
    depth, dy, dx = _repair_and_legs(ranges, sin_p, cos_p)
    angle = np.arctan2(dy, dx)
    kernel = savgol_kernel(5)
    threshold, start = float(np.float32(np.radians(angle_deg))), float(np.radians(30.0))
    got = _smooth_grow_shift(ranges, depth, angle, kernel, threshold, start)
    smooth = _smooth_columns(angle, kernel)
    assert np.array_equal(got, _growth_reference(ranges, depth, smooth, threshold, start))


@pytest.mark.parametrize("window", [5, 7, 9, 11])
def test_bogoslavskyi_smoothing_is_a_mirrored_column_filter(window):
    # their filter2D with BORDER_REFLECT101 is scipy's correlate1d with mode "mirror"
    from scipy.ndimage import correlate1d

    angle = np.random.default_rng(window).uniform(0, 1.5, (13, 7)).astype(np.float32)
    kernel = savgol_kernel(window)
    expected = correlate1d(angle.astype(np.float64), kernel.astype(np.float64), 0, mode="mirror")
    assert np.allclose(_smooth_columns(angle, kernel), expected, atol=1e-5)


def _paper_reference(ranges, elevation, max_slope_deg=10.0, sensor_height=1.73):
    """The paper's rule cell by cell in plain Python (the loop the numba kernel replaced)."""
    sin_a, cos_a, tan_lo, tan_hi = paper_tables(elevation, max_slope_deg)
    tan_slope = np.tan(np.radians(max_slope_deg))
    h, w = ranges.shape
    out = np.zeros((h, w), dtype=bool)
    for r in range(h):
        for c in range(w):
            d = ranges[r, c]
            if d <= 0.0:
                continue
            if d * np.sin(elevation[r]) > -sensor_height + tan_slope * d * np.cos(elevation[r]):
                continue
            p = r
            if r == 0 or ranges[r - 1, c] <= 0.0:
                p = r + 1
                if p >= h or ranges[p, c] <= 0.0:
                    continue
            d1, d2 = ranges[p - 1, c], ranges[p, c]
            num, den = d2 * sin_a[p], d1 - d2 * cos_a[p]
            out[r, c] = den > 0.0 and tan_lo[p] * den <= num <= tan_hi[p] * den
    return out


@settings(max_examples=150, deadline=None)
@given(
    st.integers(1, 9).flatmap(
        lambda h: arrays(
            np.float32,
            (h, 5),
            elements=st.sampled_from([0.0, 1.0, 3.5, 4.0, 4.2, 5.0, 6.5, 9.0, 12.0, 30.0]),
        )
    )
)
def test_paper_kernel_equals_the_rule_cell_by_cell(ranges):
    h = ranges.shape[0]
    elevation = np.radians(np.linspace(-8.0, -24.0, h)) if h > 1 else np.radians([-15.0])
    image = RangeImage(ranges, elevation, np.flatnonzero(ranges.reshape(-1)), "native")
    assert np.array_equal(paper_ground(image), _paper_reference(ranges, elevation))


@pytest.mark.parametrize("name", ["paper", "bogoslavskyi", "column"])
def test_every_remover_gives_one_typed_ground_step(small_sample, name):
    """The one contract: ``extract(image, points) -> Ground``; a per-pixel remover's points take
    their pixel's decision and its clusterers see the image itself; the column remover's held
    cells are never ground, are attached as the table says, and its decided points that left
    their pixel are ground."""
    from flic_cli.ground import REMOVERS
    from flic_cli.ground.base import Ground, point_ground

    remover = REMOVERS[name]()
    for frame, image in list(_frames(small_sample))[:2]:
        ground = remover.extract(image, frame.points)
        assert isinstance(ground, Ground)
        assert ground.mask.shape == image.shape and ground.mask.dtype == bool
        assert not ground.mask[image.ranges == 0].any()
        if name != "column":
            assert ground.image is image and ground.decided is None and ground.held is None
            assert np.array_equal(ground.on_ground, point_ground(image, ground.mask))
            assert ground.left_out is ground.mask
            continue
        assert not (ground.held & ground.mask).any()
        assert np.array_equal(ground.left_out, ground.mask | ground.held)
        assert np.array_equal(np.sort(ground.attached[:, 0]), np.flatnonzero(ground.held))
        counts = ground.image.point_counts().reshape(-1)
        assert np.array_equal(ground.attached[:, 2], counts[ground.attached[:, 0]])
        left = (ground.image.point_pixel < 0) & (image.point_pixel >= 0)
        assert ground.on_ground[left].all()


def test_a_ground_step_has_held_cells_and_their_attachments_together():
    from flic_cli.ground.base import Ground

    image = RangeImage(np.ones((2, 3), np.float32), np.zeros(2), np.arange(6), "native")
    none = np.zeros((2, 3), dtype=bool)
    with pytest.raises(ValueError, match="held"):
        Ground(none, image, held=none)
    with pytest.raises(ValueError, match="held"):
        Ground(none, image, attached=np.zeros((0, 3), np.int64))
    step = Ground.from_mask(image, [[1, 0, 0], [0, 0, 0]])
    assert step.mask.dtype == bool and step.on_ground.tolist() == [1, 0, 0, 0, 0, 0]
