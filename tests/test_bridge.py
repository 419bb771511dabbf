"""Bridge against the graph its docstring defines, built by brute force from 3D coordinates."""

from __future__ import annotations

import numpy as np
import pytest
import reference_kernels  # tests/reference_kernels.py: the kernels before issue 11's rework
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from oracles import (
    canonical,
    graph_components,
    image_components,
    range_images,
    same_partition,
    seen_through_joins,
    surface_scenes,
    xyz_of,
)

from flic_cli.methods import Bridge, bridge_labels, flic_labels
from flic_cli.range_image import RangeImage, from_sensor_image

LEFT, UP = (0, -1), (-1, 0)
DIAGONALS = ((-1, -1), (-1, 1))


def column_neighbours(node, ranges, rq, cq):
    """Ranges of the first node above and the first node below pixel (rq, cq) in its column
    (the ones that exist)."""
    h = node.shape[0]
    up = next((ranges[r2, cq] for r2 in range(rq - 1, -1, -1) if node[r2, cq]), None)
    down = next((ranges[r2, cq] for r2 in range(rq + 1, h) if node[r2, cq]), None)
    return [float(x) for x in (up, down) if x is not None]


def level_spacing(elevation, r, rq):
    """Footprint spacing per metre of height of a level surface between the beams of rows r and
    rq, or None where they do not both look down (no level link above the sensor)."""
    a, b = float(elevation[r]), float(elevation[rq])
    if a >= 0.0 or b >= 0.0:
        return None
    return abs(1.0 / np.tan(b) - 1.0 / np.tan(a))


def level_pair(pts, elevation, a, b, level, margins):
    """Whether node b (above a in its column) lies within ``tol`` footprints of where the level
    surface through a meets b's beam, closer than ``L = margin F <= cap`` (F: the footprint
    spacing at a's height); every test's margin is appended to ``margins``."""
    spacing = level_spacing(elevation, a[0], b[0])
    if spacing is None:
        return False
    tol, margin, cap = level[:3]
    za, zb = pts[a][2], pts[b][2]
    foot = abs(za) * spacing
    lim = margin * foot
    dz = tol * foot * abs(np.tan(elevation[b[0]]))
    dist = float(np.linalg.norm(pts[a] - pts[b]))
    margins.extend([abs(zb - za) - dz, dist - lim, lim - cap])
    return abs(zb - za) < dz and dist < lim and lim <= cap


def bridge_graph(
    ranges,
    elevation,
    mask,
    threshold,
    gamma_deg,
    reach,
    fixed_side_gaps=True,
    level=None,
    azimuth_offset=None,
    open_holes=None,
):
    """Edges of the Bridge graph, walked exactly as the module docstring says; ``level``:
    (tolerance, margin, cap, support: "none", "either" or "beyond") of the level rule of the up
    walk, or None (off);
    ``azimuth_offset``: (H,) of every row, radians (the 3D points from the true directions);
    ``open_holes``: the most open holes a sideways walk crosses, or None (no limit).

    Returns the edges and, for every distance test made, ``distance - t_p`` (to stay away from
    ties between float32 ranges and float64 coordinates) and, for every gap test, the smallest
    ``|range difference| - t_p`` over the column.
    """
    h, w = ranges.shape
    pts = xyz_of(ranges, elevation, azimuth_offset)
    node = mask & (ranges > 0)
    edges, margins = [], []
    for r in range(h):
        for c in range(w):
            if not node[r, c]:
                continue
            d = ranges[r, c]
            t_far = max(threshold, float(d) * np.sin(np.radians(gamma_deg)))
            ends = {}
            for dr, dc in (LEFT, UP, *DIAGONALS):
                if (dr, dc) in DIAGONALS and ends.get(LEFT) == 1 and ends.get(UP) == 1:
                    break  # inside a surface: no diagonal walks
                k_max = min(reach, r if dr else reach, w - 1 if dc else reach)
                crossed_gap = False  # an open gap (not a hole in p's surface) passed
                n_open = 0  # open holes passed: no node within t_far of d above or below
                for k in range(1, k_max + 1):
                    rq, cq = r + k * dr, (c + k * dc) % w
                    if not node[rq, cq]:
                        if ranges[rq, cq] > d:
                            break  # a range beyond p outside the mask: free space
                        if open_holes is not None and dc != 0:
                            near = column_neighbours(node, ranges, rq, cq)
                            margins.extend(abs(x - float(d)) - t_far for x in near)
                            n_open += not any(abs(x - float(d)) < t_far for x in near)
                            if n_open > open_holes:
                                break
                        if fixed_side_gaps and dc != 0:
                            # open: the first node above or below is beyond d + t_far (the
                            # scan sees through the gap's column) and neither is within t_far
                            # of d (a hole in p's surface would show p's surface)
                            near = column_neighbours(node, ranges, rq, cq)
                            margins.extend(abs(x - float(d)) - t_far for x in near)
                            closed = any(abs(x - float(d)) < t_far for x in near)
                            through = any(x > float(d) + t_far for x in near)
                            crossed_gap |= through and not closed
                        continue  # a hole
                    tp = threshold if crossed_gap else t_far
                    dist = float(np.linalg.norm(pts[r, c] - pts[rq, cq]))
                    margins.append(dist - tp)
                    linked = dist < tp
                    if level and (dr, dc) == UP and not linked:
                        # level with p, and by the support: nothing more ("none"), the node
                        # right above q level with q ("beyond"), or that or the node right below
                        # p level with p ("either")
                        def lv(a, b):
                            return (
                                node[a]
                                and node[b]
                                and level_pair(pts, elevation, a, b, level, margins)
                            )

                        below, above = (r + 1, c), (rq - 1, cq)
                        linked = lv((r, c), (rq, cq)) and (
                            level[3] == "none"
                            or (level[3] == "either" and r + 1 < h and lv(below, (r, c)))
                            or (rq >= 1 and lv((rq, cq), above))
                        )
                    if linked:
                        edges.append((r * w + c, rq * w + cq))
                        ends[(dr, dc)] = k
                        break
                    if ranges[rq, cq] > d:
                        break  # free space beside p
    return edges, margins


SUPPORTS = st.sampled_from(["none", "either", "beyond"])

#: Bridge's level rule as it is by default, as :func:`bridge_graph` takes it.
DEFAULT_LEVEL = (
    Bridge.level_tolerance,
    Bridge.level_margin,
    Bridge.level_cap_m,
    Bridge.level_support,
)
#: The level rule off, as :func:`bridge_labels` takes it.
NO_LEVEL = (0.0, 1.5, 2.0, "none")

#: Bridge's parameters as the graph tests draw them (the level rule: None = off).
BRIDGE_PARAMS = dict(
    threshold=st.floats(0.2, 3.0),
    gamma=st.sampled_from([0.0, 1.0, 2.0, 5.0]),
    reach=st.integers(1, 20),
    min_size=st.integers(1, 10),
    fixed=st.booleans(),
    open_holes=st.one_of(st.none(), st.integers(0, 4)),
    level=st.one_of(
        st.none(),
        st.tuples(st.floats(0.05, 1.0), st.floats(0.5, 3.0), st.floats(0.3, 6.0), SUPPORTS),
    ),
)


@settings(max_examples=400, deadline=None)
@given(scene=surface_scenes(), **BRIDGE_PARAMS)
def test_bridge_equals_components_of_its_graph(
    scene, threshold, gamma, reach, min_size, fixed, open_holes, level
):
    ranges, elevation, mask, weights = scene
    edges, margins = bridge_graph(
        ranges, elevation, mask, threshold, gamma, reach, fixed, level, open_holes=open_holes
    )
    assume(all(abs(m) > 1e-4 for m in margins))
    node = mask & (ranges > 0)
    expected = image_components(ranges.shape, node, edges, min_size, weights)
    lv = level or NO_LEVEL
    got = bridge_labels(
        ranges, elevation, threshold, gamma, reach, min_size, mask, weights, fixed, *lv,
        open_holes_px=open_holes,
    )  # fmt: skip
    np.testing.assert_array_equal(got, expected)


@st.composite
def offset_scenes(draw):
    """:func:`oracles.surface_scenes` with an azimuth offset per row (Ouster's
    ``beam_azimuth_angles``) of up to 3 columns either way, radians."""
    ranges, elevation, mask, weights = draw(surface_scenes())
    h, w = ranges.shape
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    offset = rng.uniform(-3.0, 3.0, h) * (2.0 * np.pi / w)
    return ranges, elevation, mask, weights, offset


@settings(max_examples=300, deadline=None)
@given(scene=offset_scenes(), **BRIDGE_PARAMS)
def test_bridge_with_azimuth_offsets_equals_components_of_its_true_3d_graph(
    scene, threshold, gamma, reach, min_size, fixed, open_holes, level
):
    # the graph's distances from the 3D points of each pixel's true direction (its row's
    # elevation, its column's centre plus its row's azimuth offset)
    ranges, elevation, mask, weights, offset = scene
    edges, margins = bridge_graph(
        ranges, elevation, mask, threshold, gamma, reach, fixed, level, offset, open_holes
    )
    assume(all(abs(m) > 1e-4 for m in margins))
    node = mask & (ranges > 0)
    expected = image_components(ranges.shape, node, edges, min_size, weights)
    lv = level or NO_LEVEL
    got = bridge_labels(
        ranges, elevation, threshold, gamma, reach, min_size, mask, weights, fixed, *lv, offset,
        open_holes,
    )  # fmt: skip
    np.testing.assert_array_equal(got, expected)


@settings(max_examples=100, deadline=None)
@given(scene=offset_scenes(), threshold=st.floats(0.2, 3.0), reach=st.integers(1, 20))
def test_bridge_reads_the_azimuth_offsets_from_the_image(scene, threshold, reach):
    # a sensor image (one point per valid pixel) carries the offsets; Bridge's labels per point
    # are the true 3D graph's
    ranges, elevation, _, _, offset = scene
    everything = np.ones(ranges.shape, bool)
    edges, margins = bridge_graph(
        ranges, elevation, everything, threshold, 2.0, reach, False, DEFAULT_LEVEL, offset,
        Bridge.open_holes_px,
    )  # fmt: skip
    assume(all(abs(m) > 1e-4 for m in margins))
    expected = image_components(ranges.shape, ranges > 0, edges, 1, np.ones(ranges.shape))
    img = from_sensor_image(ranges, elevation, offset)
    got = Bridge(threshold, 2.0, reach, 1).segment(img, img.to_points()[img.point_pixel], None)
    np.testing.assert_array_equal(got, expected.reshape(-1)[img.point_pixel])


@settings(max_examples=300, deadline=None)
@given(
    scene=surface_scenes(),
    threshold=st.floats(0.2, 3.0),
    gamma=st.sampled_from([0.0, 1.0, 2.0, 5.0]),
    reach=st.integers(1, 20),
    min_size=st.integers(1, 10),
    masked=st.booleans(),
    weighted=st.booleans(),
)
def test_bridge_gives_the_labels_of_the_previous_kernel(
    scene, threshold, gamma, reach, min_size, masked, weighted
):
    ranges, elevation, mask, weights = scene
    mask = mask if masked else None
    weights = weights if weighted else None
    np.testing.assert_array_equal(
        bridge_labels(
            ranges, elevation, threshold, gamma, reach, min_size, mask, weights, False, *NO_LEVEL
        ),
        reference_kernels.bridge_labels(
            ranges, elevation, threshold, gamma, reach, min_size, mask, weights
        ),
    )  # the rules for gaps beside (fixed_side_gaps) and level surfaces came after that kernel


@settings(max_examples=200, deadline=None)
@given(scene=surface_scenes(), threshold=st.floats(0.2, 3.0))
def test_reach_one_refines_nothing_of_flic(scene, threshold):
    # With reach 1 and a fixed threshold every FLIC (0 MC) edge is a Bridge edge: each FLIC
    # cluster lies inside one Bridge cluster.
    ranges, elevation, mask, _ = scene
    fl = flic_labels(ranges, elevation, threshold, 1, mask=mask & (ranges > 0))
    br = bridge_labels(ranges, elevation, threshold, 0.0, 1, 1, mask)
    for k in range(1, fl.max() + 1):
        assert np.unique(br[fl == k]).size == 1


WIDTH = 2048
ELEVATION = np.radians(np.linspace(2.0, -24.9, 64))


def wall(d_m: float, cols: slice, rows: slice = slice(20, 40)) -> np.ndarray:
    ranges = np.zeros((64, WIDTH), np.float32)
    ranges[rows, cols] = d_m
    return ranges


def test_bridges_a_hole_and_reaches_past_a_pole():
    ranges = wall(10.0, slice(100, 160))
    ranges[25:35, 120:124] = 0.0  # missing returns (dark paint)
    ranges[:, 140:143] = np.where(ranges[:, 140:143] > 0, 6.0, 0.0)  # a pole 4 m in front
    labels = bridge_labels(ranges, ELEVATION, min_size=1)
    wall_ids = np.unique(labels[(ranges == 10.0)])
    assert wall_ids.size == 1 and wall_ids[0] > 0  # one wall, holes and pole bridged
    assert np.unique(labels[ranges == 6.0]).size == 1
    assert labels[ranges == 6.0][0] != wall_ids[0]  # the pole is its own cluster
    # FLIC 0 MC cuts the wall at the pole
    assert np.unique(flic_labels(ranges, ELEVATION, 0.8, 1)[ranges == 10.0]).size == 2


def test_free_space_between_two_surfaces_is_not_jumped():
    # two boards 0.3 m apart at 8 m (about 12 columns at 2048): with a wall seen between them
    # they stay apart; with nothing seen between them (sky) the walk without a limit on open
    # holes reaches over the gap, the default walk stops after 4 of its 12 open holes
    step = 2 * np.pi / WIDTH
    gap_cols = int(round(0.3 / 8.0 / step))
    ranges = wall(8.0, slice(100, 140))
    ranges[20:40, 140 + gap_cols : 180] = 8.0
    behind = ranges.copy()
    behind[20:40, 140 : 140 + gap_cols] = 30.0
    for open_holes in (None, 4):
        apart = bridge_labels(behind, ELEVATION, 0.4, 2.0, 16, 1, open_holes_px=open_holes)
        assert apart[30, 120] != apart[30, 160]
    joined = bridge_labels(ranges, ELEVATION, 0.4, 2.0, 16, 1, open_holes_px=None)
    assert joined[30, 120] == joined[30, 160]
    default = bridge_labels(ranges, ELEVATION, 0.4, 2.0, 16, 1)
    assert default[30, 120] != default[30, 160]


def test_ground_pixels_show_free_space_but_are_not_nodes():
    ranges = wall(8.0, slice(100, 140))
    ranges[20:40, 150:180] = 8.0
    ranges[20:40, 140:150] = 9.0  # ground beyond the boards, visible between them
    mask = ranges != 9.0
    labels = bridge_labels(ranges, ELEVATION, 1.5, 0.0, 16, 1, mask)
    assert labels[30, 120] != labels[30, 160] and (labels[ranges == 9.0] == 0).all()
    # the same gap as a hole (nothing there) is bridged by the walk without a limit on open
    # holes; the default walk stops after 4 of its 10 columns, empty over the boards' height
    ranges[ranges == 9.0] = 0.0
    labels = bridge_labels(ranges, ELEVATION, 1.5, 0.0, 16, 1, open_holes_px=None)
    assert labels[30, 120] == labels[30, 160]
    labels = bridge_labels(ranges, ELEVATION, 1.5, 0.0, 16, 1)
    assert labels[30, 120] != labels[30, 160]


def test_bridge_component_counts_points_and_maps_to_points():
    from flic_cli.ground.base import Ground

    ranges = wall(6.0, slice(100, 130), slice(30, 32))  # 60 pixels
    pix = np.repeat(np.flatnonzero(ranges.reshape(-1) > 0), 2)  # two points per pixel
    img = RangeImage(ranges, ELEVATION, pix, "rings")
    pts = np.zeros((pix.size, 3), np.float32)
    assert (Bridge().segment(img, pts, None) == 1).all()
    assert (Bridge(min_size=121).segment(img, pts, None) == 0).all()
    ground = np.zeros(ranges.shape, bool)
    ground[31] = True
    assert (Bridge(min_size=60).segment(img, pts, Ground.from_mask(img, ground)) > 0).sum() == 60


def test_bridge_is_a_configurable_method(tmp_path):
    from flic_cli.config import load_config
    from flic_cli.errors import FlicInputError
    from flic_cli.methods import KINDS

    assert KINDS["bridge"] is Bridge
    assert load_config().method("bridge").method == Bridge()
    path = tmp_path / "mine.toml"
    path.write_text('[methods.mine]\nkind = "bridge"\nthreshold_m = 0.5\nreach_px = 4\n')
    assert load_config(path).method("mine").method == Bridge(threshold_m=0.5, reach_px=4)
    path.write_text('[methods.bad]\nkind = "bridge"\nreach_px = 0\n')
    with pytest.raises(FlicInputError, match=r"mine.toml: \[methods.bad\] reach_px"):
        load_config(path)


def _person(x: float, y: float, instance: int):
    from flic_cli.sample import SENSOR_HEIGHT_M, Box

    # 0.5 m wide, 0.35 m deep, 1.75 m tall, standing on the road
    return Box((x, y, -SENSOR_HEIGHT_M + 0.875), (0.175, 0.25, 0.875), 0.0, 30, instance)


# Beyond about 14 m the link distance d sin(2 deg) exceeds the 0.5 m gap; where only holes
# (removed ground, sky) lie between them, two such people join unless fixed_side_gaps is set
# (test_two_people_half_a_metre_apart_far_away_are_two_clusters; results/bridge-cases/).
@pytest.mark.parametrize("distance_m", [6.0, 9.0, 12.0])
@pytest.mark.parametrize("behind", ["nothing", "facade"])
def test_two_people_one_metre_apart_stay_two_clusters(distance_m, behind):
    # Two people side by side, centres 1 m apart (a 0.5 m gap), in front of the sensor, cast
    # with the sample's HDL-64E model; ground points removed as in the "No Ground" setting.
    from flic_cli.sample import Box, Ground

    boxes = [_person(distance_m, -0.5, 1), _person(distance_m, 0.5, 2)]
    if behind == "facade":
        boxes.append(Box((distance_m + 8.0, 0.0, 2.0), (0.2, 10.0, 5.0), 0.0, 50))
    ground = Ground(0.0, (-4.0, 4.0), (-8.0, 8.0))
    ranges, elevation, instance = _cast_without_ground(boxes, ground)
    labels = bridge_labels(ranges, elevation, min_size=30)
    a = labels[instance == 1]
    b = labels[instance == 2]
    assert a.size > 100 and b.size > 100
    la = np.bincount(a).argmax()
    lb = np.bincount(b).argmax()
    assert la > 0 and lb > 0 and la != lb
    assert (a == la).mean() > 0.95 and (b == lb).mean() > 0.95


def _cast_without_ground(boxes, ground=None):
    """``boxes`` on ``ground`` (None: the flat road), cast with the sample's HDL-64E model at 2048
    columns, the ground's returns removed as in the "No Ground" setting: (ranges, elevation,
    instance)."""
    from flic_cli.classes import GROUND_CLASSES
    from flic_cli.sample import HDL64_PITCH_DEG, Ground, Scene, cast

    scene = Scene(0, 0, np.eye(3, 4), ground or Ground.flat(), boxes, [])
    elevation = -np.radians(HDL64_PITCH_DEG)
    img0 = RangeImage(np.zeros((64, WIDTH), np.float32), elevation, np.zeros(0, np.int64), "x")
    ranges, semantic, instance = cast(
        scene, HDL64_PITCH_DEG, img0.azimuth, np.random.default_rng(0)
    )
    ranges[np.isin(semantic, list(GROUND_CLASSES))] = 0.0
    return ranges.astype(np.float32), elevation, instance


def _two_people_image(distance_m: float, gap_m: float):
    """Two people side by side ``gap_m`` apart at ``distance_m`` on a flat road, a facade 8 m
    behind them, cast with the sample's HDL-64E model at 2048 columns; the ground's returns
    removed as in the "No Ground" setting (between the legs the scan shows nothing, higher up
    it sees the facade through the gap)."""
    from flic_cli.sample import Box

    half = (gap_m + 0.5) / 2
    boxes = [_person(distance_m, -half, 1), _person(distance_m, half, 2)]
    boxes.append(Box((distance_m + 8.0, 0.0, 2.0), (0.2, 10.0, 5.0), 0.0, 50))
    return _cast_without_ground(boxes)


def assert_people_whole(labels, instance, apart):
    """Each of the two people (instance 1, 2) is one cluster of more than 40 pixels; they are two
    clusters when ``apart``, else one."""
    a, b = labels[instance == 1], labels[instance == 2]
    assert a.size > 40 and b.size > 40
    la, lb = np.bincount(a).argmax(), np.bincount(b).argmax()
    assert la > 0 and lb > 0 and (a == la).all() and (b == lb).all()
    assert (la != lb) == apart


@pytest.mark.parametrize("distance_m", [20.0, 25.0])
def test_two_people_half_a_metre_apart_far_away_are_two_clusters(distance_m):
    ranges, elevation, instance = _two_people_image(distance_m, 0.5)
    # without a limit on open holes they joined; the rule for gaps beside or the default limit
    # keeps them apart
    for fixed, open_holes, apart in ((True, None, True), (False, None, False), (False, 4, True)):
        labels = bridge_labels(
            ranges, elevation, min_size=10, fixed_side_gaps=fixed, open_holes_px=open_holes
        )
        assert_people_whole(labels, instance, apart)


def test_a_hole_in_a_surface_is_still_bridged_at_the_far_link_distance():
    # A wall at 20 m with 8 empty columns (0.49 m, below d sin(2 deg) = 0.70 m, above the
    # 0.35 m threshold): a band of missing returns with the wall above and below it is a hole
    # in the wall and bridged; the same columns empty over the wall's whole height, with a
    # building seen through them above, are a gap between two things.
    # (the rule for gaps beside on its own: without the default limit on open holes)
    ranges = wall(20.0, slice(100, 160))
    hole = ranges.copy()
    hole[26:34, 126:134] = 0.0
    labels = bridge_labels(hole, ELEVATION, min_size=1, fixed_side_gaps=True, open_holes_px=None)
    assert np.unique(labels[hole > 0]).size == 1
    gap = ranges.copy()
    gap[:, 126:134] = 0.0
    gap[10:20, 120:140] = 45.0  # a building behind, seen above the wall
    labels = bridge_labels(gap, ELEVATION, min_size=1, fixed_side_gaps=True, open_holes_px=None)
    assert labels[30, 110] > 0 and labels[30, 150] > 0 and labels[30, 110] != labels[30, 150]
    assert np.unique(labels[gap == 20.0]).size == 2
    old = bridge_labels(gap, ELEVATION, min_size=1, fixed_side_gaps=False, open_holes_px=None)
    assert np.unique(old[gap == 20.0]).size == 1
    # with nothing seen through the gap's column there is no sign of free space: bridged
    gap[10:20] = 0.0
    labels = bridge_labels(gap, ELEVATION, min_size=1, fixed_side_gaps=True, open_holes_px=None)
    assert np.unique(labels[gap == 20.0]).size == 1
    # a hole whose column shows a farther thing above it (a window) and the wall below it is
    # still a hole in the wall
    window = hole.copy()
    window[20:26, 126:134] = 35.0
    labels = bridge_labels(window, ELEVATION, min_size=1, fixed_side_gaps=True, open_holes_px=None)
    assert np.unique(labels[window == 20.0]).size == 1


@pytest.mark.parametrize("distance_m", [16.0, 20.0, 25.0])
def test_open_holes_keep_two_people_apart_with_nothing_behind_them(distance_m):
    # two people 0.5 m apart, ground removed, nothing seen between them: the gap is open
    # holes only (8-10 columns at 16-20 m), which fixed_side_gaps cannot tell from a hole in a
    # surface (nothing farther is seen through it)
    ranges, elevation, instance = _two_people_image(distance_m, 0.5)
    for open_holes, apart in ((3, True), (None, False)):
        labels = bridge_labels(ranges, elevation, min_size=10, open_holes_px=open_holes)
        assert_people_whole(labels, instance, apart)


def test_a_hole_that_its_surface_closes_is_bridged_with_open_holes_limited():
    # 8 empty columns inside a wall at 20 m: the wall above and below closes them, so no open
    # hole is crossed even with open_holes_px = 0; the same columns empty over the wall's whole
    # height are open holes: the walk stops after open_holes_px of them
    ranges = wall(20.0, slice(100, 160))
    hole = ranges.copy()
    hole[26:34, 126:134] = 0.0
    labels = bridge_labels(hole, ELEVATION, min_size=1, open_holes_px=0)
    assert np.unique(labels[hole > 0]).size == 1
    gap = ranges.copy()
    gap[:, 126:134] = 0.0
    for open_holes, parts in ((7, 2), (8, 1), (None, 1)):
        labels = bridge_labels(gap, ELEVATION, min_size=1, open_holes_px=open_holes)
        assert np.unique(labels[gap == 20.0]).size == parts


@st.composite
def far_scenes(draw):
    """2048-column images with a few far boxes side by side, holes, and background seen above
    some gaps: the walks over open gaps and holes that ``fixed_side_gaps`` decides."""
    h = draw(st.integers(4, 14))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    ranges = np.zeros((h, WIDTH), np.float32)
    c = 0
    for _ in range(draw(st.integers(1, 4))):
        c += int(rng.integers(0, 10))
        width = int(rng.integers(2, 12))
        top = int(rng.integers(0, h - 1))
        ranges[top:, c : c + width] = rng.uniform(12.0, 35.0)
        c += width
    back = rng.random((h, WIDTH)) < 0.5
    back[int(rng.integers(1, h)) :] = False
    ranges[(ranges == 0) & back] = 48.0
    ranges *= 1.0 + rng.normal(0.0, 0.003, ranges.shape).astype(np.float32)
    ranges[rng.random((h, WIDTH)) < draw(st.sampled_from([0.0, 0.1, 0.3]))] = 0.0
    elevation = np.radians(np.linspace(2.0, 2.0 - 0.43 * (h - 1), h))
    return ranges.astype(np.float32), elevation


@settings(max_examples=60, deadline=None)
@given(
    scene=far_scenes(),
    reach=st.sampled_from([4, 12]),
    fixed=st.booleans(),
    open_holes=st.sampled_from([None, 0, 2, 4]),
)
def test_bridge_with_fixed_side_gaps_equals_its_graph_on_far_scenes(
    scene, reach, fixed, open_holes
):
    ranges, elevation = scene
    mask = np.ones(ranges.shape, bool)
    edges, margins = bridge_graph(
        ranges, elevation, mask, 0.35, 2.0, reach, fixed, open_holes=open_holes
    )
    assume(all(abs(m) > 1e-4 for m in margins))
    expected = image_components(ranges.shape, ranges > 0, edges, 1, np.ones(ranges.shape))
    got = bridge_labels(
        ranges, elevation, 0.35, 2.0, reach, 1, None, None, fixed, open_holes_px=open_holes
    )
    np.testing.assert_array_equal(got, expected)


@st.composite
def box_scenes(draw):
    """Range images of boxes on removed ground, seen by downward beams: per group of columns a
    vertical face at horizontal distance x up to height z below the sensor, and the box's level
    top behind it (length l), then free space or a farther box; noise, holes, a mask. The up
    walks there cross from faces onto tops, where the level-surface rule decides."""
    h = draw(st.integers(2, 12))
    w = draw(st.integers(1, 24))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    elevation = np.radians(np.sort(rng.uniform(-24.0, -0.5, h))[::-1])
    ranges = np.zeros((h, w))
    cuts = np.sort(rng.integers(0, w + 1, rng.integers(0, 4)))
    groups = np.searchsorted(cuts, np.arange(w), side="right")
    for g in range(cuts.size + 1):
        x, z, length = rng.uniform(3.0, 25.0), -rng.uniform(0.2, 1.6), rng.uniform(0.5, 6.0)
        for r, e in enumerate(elevation):
            beam_z = x * np.tan(e)  # the beam's height at the face
            if beam_z < z:
                d = x / np.cos(e)  # the face
            elif z / np.tan(e) < x + length:
                d = z / np.sin(e)  # the top
            else:
                d = 0.0
            ranges[r, groups == g] = d
    noise = draw(st.sampled_from([0.0, 0.003, 0.01]))
    ranges *= 1.0 + rng.normal(0.0, noise, (h, w))
    ranges[rng.random((h, w)) < draw(st.sampled_from([0.0, 0.2, 0.4]))] = 0.0
    mask = rng.random((h, w)) >= draw(st.sampled_from([0.0, 0.2]))
    return ranges.astype(np.float32), elevation, mask


@settings(max_examples=300, deadline=None)
@given(
    scene=box_scenes(),
    threshold=st.floats(0.2, 1.0),
    gamma=st.sampled_from([0.0, 2.0]),
    reach=st.integers(1, 12),
    level=st.tuples(st.floats(0.05, 1.0), st.floats(0.5, 3.0), st.floats(0.3, 6.0), SUPPORTS),
)
def test_bridge_with_level_surfaces_equals_its_graph_on_boxes(
    scene, threshold, gamma, reach, level
):
    ranges, elevation, mask = scene
    edges, margins = bridge_graph(ranges, elevation, mask, threshold, gamma, reach, False, level)
    assume(all(abs(m) > 1e-4 for m in margins))
    node = mask & (ranges > 0)
    expected = image_components(ranges.shape, node, edges, 1, np.ones(ranges.shape))
    got = bridge_labels(ranges, elevation, threshold, gamma, reach, 1, mask, None, False, *level)
    np.testing.assert_array_equal(got, expected)


def _vehicle_image(kind: str, distance_m: float):
    """A car seen from behind (its rear face at ``distance_m``) or a van seen from the front
    (a 1.0 m high hood box, the cabin's face 0.7 m behind it), straight ahead on a flat road,
    cast with the sample's HDL-64E model at 2048 columns, the ground's returns removed."""
    from flic_cli.sample import Box, Ground, car

    zg = -Ground.flat().sensor_height
    if kind == "car":
        boxes = car(distance_m + 2.2, 0.0, 1)
    else:  # hood box 0.7 m long, then the cabin box 3.8 m long, one object; "pair": the cabin
        # box 0.5 m farther, a second object (scripts/bridge_cases.py's box-pair)
        gap, second = (0.5, 2) if kind == "pair" else (0.0, 1)
        boxes = [
            Box((distance_m + 0.35, 0.0, zg + 0.625), (0.35, 0.95, 0.375), 0.0, 20, 1),
            Box((distance_m + 2.6 + gap, 0.0, zg + 1.175), (1.9, 0.95, 0.925), 0.0, 20, second),
        ]
    return _cast_without_ground(boxes)


@pytest.mark.parametrize(("kind", "distance_m"), [("car", 8.0), ("van", 8.0)])
def test_a_box_shaped_vehicle_is_one_cluster_with_the_bare_level_rule(kind, distance_m):
    # Without the rule the vehicle splits where the scan passes from its face onto its top or
    # hood (rows of a level surface lie d^2 de / h apart there, more than the 0.35 m link);
    # with the level-surface link of the up walk and no support asked, the face and the top
    # are one cluster. (From 12 m on both stay split: the footprint there exceeds the cap over
    # the margin, or the hit lies beyond a quarter footprint from the level prediction;
    # results/bridge-cases/, "A rule for cause 2".)
    ranges, elevation, instance = _vehicle_image(kind, distance_m)
    obj = instance == 1
    assert obj.sum() > 200
    without = bridge_labels(ranges, elevation, min_size=1, level_tolerance=0.0)
    assert np.unique(without[obj]).size > 1
    labels = bridge_labels(ranges, elevation, min_size=1, level_support="none")
    assert np.unique(labels[obj]).size == 1 and labels[obj][0] > 0
    assert ((labels == labels[obj][0]) == obj).all()  # nothing else joins it


@pytest.mark.parametrize("distance_m", [7.0, 8.0])
def test_a_car_seen_from_behind_is_one_cluster_with_the_default_level_rule(distance_m):
    # The sample's car model (body, roof, window pillars) from behind: without the level rule
    # its rear face, the rows of its top and its pillars are five or more clusters, the largest
    # under 70 % of it; with the default rule (a level node beyond q) one cluster holds more than
    # 90 % of it (its top's last row, with nothing level beyond it, stays apart) and nothing else
    ranges, elevation, instance = _vehicle_image("car", distance_m)
    obj = instance == 1
    without = bridge_labels(ranges, elevation, min_size=1, level_tolerance=0.0)
    _, sizes = np.unique(without[obj], return_counts=True)
    assert sizes.size >= 5 and sizes.max() < 0.7 * obj.sum()
    labels = bridge_labels(ranges, elevation, min_size=1)
    ids, sizes = np.unique(labels[obj], return_counts=True)
    main = ids[np.argmax(sizes)]
    assert main > 0 and sizes.max() > 0.9 * obj.sum()
    assert not ((labels == main) & ~obj).any()


def _behind_a_car_image(distance_m: float, behind_m: float, size: tuple[float, float, float]):
    """The car of :func:`_vehicle_image` (rear face at ``distance_m``, 4.4 m long) and a box
    standing ``behind_m`` beyond its front (instance 2, a person or a motorcycle by ``size``),
    seen through the car's windows above its body, the ground's returns removed."""
    from flic_cli.sample import car, person

    boxes = [*car(distance_m + 2.2, 0.0, 1), person(distance_m + 4.4 + behind_m, 0.0, 2, size=size)]
    return _cast_without_ground(boxes)


@pytest.mark.parametrize(
    ("distance_m", "behind_m", "size"),
    [(6.0, 0.6, (0.5, 0.4, 1.75)), (8.0, 1.0, (0.5, 0.4, 1.75)), (7.0, 1.5, (1.8, 0.6, 1.2))],
)
def test_what_stands_behind_a_car_stays_apart_with_the_level_node_beyond_q(
    distance_m, behind_m, size
):
    # A person or a motorcycle behind a car, seen through its windows: its first return above
    # the car's body lies at the body's height (the car hides it below that line), level with
    # the body's top. With the support "either" (the node below p, on the car's top, is level)
    # or none it joins the car; the default asks the node above q to be level with q, and on an
    # upright object it is not (module docstring, "Level surfaces").
    ranges, elevation, instance = _behind_a_car_image(distance_m, behind_m, size)
    assert (instance == 2).sum() > 50

    def joined(**level):
        labels = bridge_labels(ranges, elevation, min_size=1, **level)
        return np.intersect1d(labels[instance == 1], labels[instance == 2]).size > 0

    assert joined(level_support="either") and joined(level_support="none")
    assert not joined()


def test_no_level_link_above_the_sensor():
    # Two level surfaces 0.25 m above and 0.25 m below the sensor, each hit by three rows
    # 0.26-0.34 m apart (more than the 0.2 m link), in one column: below, the level rule links
    # the rows (a car's top; by default the last one, with no level node beyond it, stays
    # apart); above, the surface is an underside seen from below (a canopy, which a person's
    # head just beyond its edge would meet at its height) and no level link is made.
    elevation = np.radians(np.array([8.0, 7.0, 6.0, -6.0, -7.0, -8.0]))
    ranges = (0.25 / np.abs(np.sin(elevation)))[:, None].astype(np.float32)
    for support, below in (("none", slice(3, 6)), ("beyond", slice(4, 6))):
        labels = bridge_labels(ranges, elevation, 0.2, 0.0, 3, 1, level_support=support)
        assert np.unique(labels[below]).size == 1
        assert np.unique(labels[:3]).size == 3
    off = bridge_labels(ranges, elevation, 0.2, 0.0, 3, 1, level_tolerance=0.0)
    assert np.unique(off).size == 6


@pytest.mark.parametrize("distance_m", [16.0, 20.0])
def test_a_low_box_before_a_van_stays_apart_where_the_footprint_exceeds_the_cap(distance_m):
    # The hood box's top and the van's face 0.5 m behind it lie at one height: the scan cannot
    # tell them from one level surface. Beyond 12 m the footprint spacing a level surface at
    # that height would show exceeds the cap, so the level rule links nothing there and the two
    # stay apart; at 8-12 m it joins them (results/bridge-cases/, "A rule for cause 2").
    ranges, elevation, instance = _vehicle_image("pair", distance_m)
    labels = bridge_labels(ranges, elevation, min_size=1, level_tolerance=0.25)
    a, b = labels[instance == 1], labels[instance == 2]
    assert a.size > 30 and b.size > 100
    assert np.intersect1d(a, b).size == 0 and (a > 0).all() and (b > 0).all()


@settings(max_examples=150, deadline=None)
@given(
    image=range_images(),
    data=st.data(),
    reach=st.sampled_from([1, 3, 12]),
    depth=st.sampled_from([0.5, 4.0, 20.0]),
    use_classes=st.booleans(),
)
def test_seen_through_joins_equal_their_definition(image, data, reach, depth, use_classes):
    """Bridge with the seen-through rule gives the components of Bridge without it plus the
    joins that the rule's definition, applied pixel by pixel, finds (tests/oracles.py)."""
    ranges, elevation = image
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    mask = rng.random(ranges.shape) < data.draw(st.sampled_from([1.0, 0.8]))
    classes = rng.integers(0, 2, ranges.shape) if use_classes else None
    args = (ranges, elevation, 0.35, 2.0, reach, 1, mask)
    base = bridge_labels(*args, seen_through_m=0.0)
    got = bridge_labels(*args, seen_through_m=depth, classes=classes)
    node = mask & (ranges > 0)
    joins = seen_through_joins(base, ranges, node, reach, depth, classes)
    n = int(base.max()) + 1
    comp = graph_components(n, joins)
    expected = np.where(base > 0, comp[base] + 1, 0)
    np.testing.assert_array_equal(got, canonical(expected))


def window_scene(far_m: float) -> tuple[np.ndarray, np.ndarray]:
    """A bus's near side at 15 m (16 x 60 pixels of an HDL-64E-like 2048-column image) with two
    windows (rows 4-8, columns 10-25 and 32-50) through which its far side is seen ``far_m``
    behind, a pillar of near side between them."""
    ranges = np.zeros((20, 2048), np.float32)
    ranges[2:18, 5:65] = 15.0
    ranges[4:9, 10:26] = 15.0 + far_m
    ranges[4:9, 32:51] = 15.0 + far_m
    return ranges, np.radians(np.linspace(2.0, -6.0, 20))


def test_a_far_side_seen_through_windows_joins_the_near_side_with_semantics():
    ranges, elevation = window_scene(2.5)
    apart = bridge_labels(ranges, elevation, min_size=1)
    # the near side, and the far side (one cluster: Bridge walks over the nearer pillar)
    assert np.unique(apart[ranges > 0]).size == 2
    bus = np.full(ranges.shape, 16)
    joined = bridge_labels(ranges, elevation, min_size=1, seen_through_m=4.0, classes=bus)
    assert np.unique(joined[ranges > 0]).size == 1
    # too deep behind for the rule (a wall seen through both windows), or of another class
    deep = bridge_labels(*window_scene(6.0), min_size=1, seen_through_m=4.0, classes=bus)
    assert np.unique(deep[ranges > 0]).size == 2
    other = bus.copy()
    other[4:9, 10:51] = 11  # a motorcycle behind a car's windows
    kept = bridge_labels(ranges, elevation, min_size=1, seen_through_m=4.0, classes=other)
    assert np.unique(kept[ranges > 0]).size == 2


def test_a_cluster_that_stands_out_of_the_frame_is_not_seen_through():
    """A person 2.5 m behind the bus, seen through its window (nothing else behind it) and with
    the head above its roof: the person's top looks onto nothing, so it stays apart. Without
    the head it would be framed by the bus and join it (the case semantics tell apart)."""
    ranges, elevation = window_scene(2.5)
    ranges[4:9, 10:26] = ranges[4:9, 32:51] = 0.0  # the rays through the windows see nothing
    ranges[4:9, 14:20] = 17.5  # the torso through the window
    hidden = bridge_labels(ranges, elevation, min_size=1, seen_through_m=4.0)
    assert hidden[5, 15] == hidden[10, 15]
    ranges[0:2, 14:20] = 17.5  # the head above the roof (rows 2-3)
    labels = bridge_labels(ranges, elevation, min_size=1, seen_through_m=4.0)
    assert labels[0, 15] == labels[5, 15] != labels[10, 15]


def test_bridge_uses_semantics_only_in_runs_with_them():
    """Class-agnostic (evaluate's IoU, benchmark, sweeps): the rule is off, Bridge's labels those
    of Bridge without it; with semantics (segment --semantics, the oracle PQ) it joins."""
    from flic_cli.runs.pipeline import segment_with, uses_semantics

    ranges, elevation = window_scene(2.5)
    image = from_sensor_image(ranges, elevation)
    points = image.pixel_points(image.point_pixel)
    method = Bridge(min_size=1)
    bus = np.full(points.shape[0], 13)  # raw class bus
    assert uses_semantics(method)
    agnostic = segment_with(method, image, points, None, bus)
    assert np.unique(agnostic).size == 2
    assert np.unique(method.segment(image, points, None, semantics=bus)).size == 1
    always = Bridge(min_size=1, seen_through_agnostic=True).segment(image, points, None)
    assert np.unique(always).size == 1


@st.composite
def framed_labels(draw):
    """Cluster maps that frame one another: a cluster A with a farther one B inside its frame
    (0.5-5 m behind, its class that of A or not), and rectangles of other clusters (a range in
    5-15 m on a 0.5 m grid, a class 0 or 1) drawn before and after, over or across them; holes
    (no range) and returns left out (a range, no node) sprinkled in."""
    h = draw(st.integers(3, 10))
    w = draw(st.integers(3, 20))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    labels = np.zeros((h, w), np.int64)
    raw = np.zeros((h, w))
    cls = np.zeros((h, w), np.int64)

    def rectangle(k, r0, r1, c0, c1, d):
        labels[r0:r1, c0:c1] = k
        raw[r0:r1, c0:c1] = d
        cls[r0:r1, c0:c1] = rng.integers(0, 2)

    def anywhere(k):
        r0, c0 = rng.integers(0, h), rng.integers(0, w)
        rectangle(k, r0, rng.integers(r0, h) + 1, c0, rng.integers(c0, w) + 1,
                  np.round(rng.uniform(5.0, 15.0) * 2) / 2)  # fmt: skip

    k = 0
    for k in range(1, draw(st.integers(0, 3)) + 1):
        anywhere(k)
    r0, c0 = rng.integers(0, h - 2), rng.integers(0, w - 2)
    r1, c1 = rng.integers(r0 + 3, h + 1), rng.integers(c0 + 3, w + 1)
    d = np.round(rng.uniform(5.0, 12.0) * 2) / 2
    rectangle(k + 1, r0, r1, c0, c1, d)  # A
    rb = rng.integers(r0 + 1, r1 - 1)
    cb = rng.integers(c0 + 1, c1 - 1)
    rectangle(k + 2, rb, rng.integers(rb, r1 - 1) + 1, cb, rng.integers(cb, c1 - 1) + 1,
              d + rng.choice([0.5, 1.0, 3.0, 5.0]))  # fmt: skip
    for extra in range(k + 3, k + 3 + draw(st.integers(0, 3))):
        anywhere(extra)
    raw[rng.random((h, w)) < draw(st.sampled_from([0.0, 0.1, 0.3]))] = 0.0
    node = raw > 0
    left_out = node & (rng.random((h, w)) < draw(st.sampled_from([0.0, 0.1])))
    raw[left_out & (labels == 0)] = 0.0
    node &= ~left_out & (labels > 0)
    return labels * node, raw, node, cls


@settings(max_examples=300, deadline=None)
@given(
    scene=framed_labels(),
    limit=st.sampled_from([1, 2, 5, 12]),
    depth=st.sampled_from([1.0, 4.0]),
    use_classes=st.booleans(),
)
def test_the_seen_through_kernel_joins_what_its_definition_joins(scene, limit, depth, use_classes):
    """The kernel of the seen-through rule on arbitrary cluster maps that frame one another
    against the rule applied pixel by pixel (tests/oracles.py)."""
    from flic_cli.methods.bridge import _seen_through

    labels, raw, node, cls = scene
    h, w = labels.shape
    n = int(labels.max())
    parent = np.arange(n + 1, dtype=np.uint32)
    _seen_through(
        labels.reshape(-1).astype(np.uint32), parent, np.where(node, raw, 0.0).reshape(-1),
        raw.reshape(-1), cls.reshape(-1), use_classes, h, w, n, limit, depth,
    )  # fmt: skip
    joins = seen_through_joins(labels, raw, node, limit, depth, cls if use_classes else None)
    expected = graph_components(n + 1, joins)
    got = parent.astype(np.int64)
    present = np.unique(labels[node])
    assert same_partition(got[present], expected[present])
