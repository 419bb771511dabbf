"""The clusterers against brute-force graphs built from 3D coordinates."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import reference_kernels  # tests/reference_kernels.py: the kernels before issue 11's rework
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from oracles import canonical, image_components, pixel_weights, range_images, xyz_of

from flic_cli.methods import bogoslavskyi_labels, dbscan_labels, drop_small, flic_labels
from flic_cli.methods.bogoslavskyi import bogoslavskyi_beta
from flic_cli.methods.flic import flic_labels_scipy


def neighbour_pairs(h: int, w: int, maps, mc_mode: str):
    """Every pair of pixels the definition connects (direct 4-neighbours + Map Connections)."""
    sets = [((1, 1), (0, 0), True)]
    sets += [((m[0], m[1]), tuple(m[2:]) or (0, 0), mc_mode == "map") for m in maps]
    for (kr, kc), (orow, ocol), lattice in sets:
        rows = range(orow % kr, h, kr) if lattice else range(h)
        cols = list(range(ocol % kc, w, kc)) if lattice else list(range(w))
        for r in rows:
            for i, c in enumerate(cols):
                if r + kr < h:
                    yield (r, c), (r + kr, c)
                if lattice:
                    yield (r, c), (r, cols[(i + 1) % len(cols)])
                else:
                    yield (r, c), (r, (c + kc) % w)


def brute_force(ranges, valid, pairs, linked, min_size, weights=None):
    """The components of the graph whose edges are the ``pairs`` of valid pixels ``linked``."""
    h, w = ranges.shape
    edges = [
        (r1 * w + c1, r2 * w + c2)
        for (r1, c1), (r2, c2) in pairs
        if (r1, c1) != (r2, c2) and valid[r1, c1] and valid[r2, c2] and linked(r1, c1, r2, c2)
    ]
    return image_components((h, w), valid, edges, min_size, weights)


maps_strategy = st.lists(
    st.tuples(st.integers(1, 4), st.integers(1, 5), st.integers(0, 3), st.integers(0, 4)),
    max_size=3,
)


@settings(max_examples=300, deadline=None)
@given(
    image=range_images(),
    threshold=st.floats(0.3, 3.0),
    maps=maps_strategy,
    mc_mode=st.sampled_from(["map", "neighbour"]),
    min_size=st.integers(1, 12),
    data=st.data(),
)
def test_flic_equals_components_of_3d_distance_graph(
    image, threshold, maps, mc_mode, min_size, data
):
    ranges, elevation = image
    h, w = ranges.shape
    weights = data.draw(pixel_weights((h, w)))
    maps = [m[:2] if m[2] == m[3] == 0 else m for m in maps]
    pts = xyz_of(ranges, elevation)
    valid = ranges > 0
    dist = {}

    def linked(r1, c1, r2, c2):
        d = float(np.linalg.norm(pts[r1, c1] - pts[r2, c2]))
        dist[(r1, c1, r2, c2)] = d
        return d < threshold

    pairs = neighbour_pairs(h, w, maps, mc_mode)
    expected = brute_force(ranges, valid, pairs, linked, min_size, weights)
    # float32 ranges vs float64 coordinates: stay away from exact ties with the threshold
    assume(all(abs(d - threshold) > 1e-4 for d in dist.values()))
    got = flic_labels(ranges, elevation, threshold, min_size, tuple(maps), mc_mode, None, weights)
    np.testing.assert_array_equal(canonical(got), expected)
    np.testing.assert_array_equal(got, canonical(got))  # numbered 1..K in raster order


@settings(max_examples=300, deadline=None)
@given(
    image=range_images(),
    threshold=st.floats(0.3, 3.0),
    maps=maps_strategy,
    mc_mode=st.sampled_from(["map", "neighbour"]),
    min_size=st.integers(1, 12),
    data=st.data(),
)
def test_scipy_reference_equals_the_kernel(image, threshold, maps, mc_mode, min_size, data):
    ranges, elevation = image
    weights = data.draw(pixel_weights(ranges.shape))
    maps = tuple(m[:2] if m[2] == m[3] == 0 else m for m in maps)
    fast = flic_labels(ranges, elevation, threshold, min_size, maps, mc_mode, None, weights)
    ref = flic_labels_scipy(ranges, elevation, threshold, min_size, maps, mc_mode, None, weights)
    np.testing.assert_array_equal(ref, fast)


@settings(max_examples=200, deadline=None)
@given(
    image=range_images(), angle=st.floats(2.0, 60.0), min_size=st.integers(1, 12), data=st.data()
)
def test_bogoslavskyi_equals_components_of_atan2_graph(image, angle, min_size, data):
    ranges, elevation = image
    h, w = ranges.shape
    weights = data.draw(pixel_weights((h, w)))
    theta = np.radians(angle)
    pts = xyz_of(ranges, elevation)
    betas = []

    def linked(r1, c1, r2, c2):
        u, v = pts[r1, c1], pts[r2, c2]
        alpha = np.arccos(np.clip(u @ v / np.linalg.norm(u) / np.linalg.norm(v), -1, 1))
        beta = float(bogoslavskyi_beta(ranges[r1, c1], ranges[r2, c2], alpha))
        betas.append(beta)
        return beta > theta

    pairs = neighbour_pairs(h, w, [], "map")
    expected = brute_force(ranges, ranges > 0, pairs, linked, min_size, weights)
    assume(all(abs(b - theta) > 1e-5 for b in betas))
    got = bogoslavskyi_labels(ranges, elevation, angle, min_size, None, weights)
    np.testing.assert_array_equal(canonical(got), expected)


@settings(max_examples=100, deadline=None)
@given(image=range_images())
def test_image_points_are_the_points_from_the_angles(image):
    # the oracles above build their graphs from xyz_of; flic's own points must be the same
    from flic_cli.range_image import RangeImage

    ranges, elevation = image
    img = RangeImage(ranges, elevation, np.zeros(0, np.int64), "native")
    got = img.to_points().astype(np.float64).reshape(*ranges.shape, 3)
    np.testing.assert_allclose(got, xyz_of(ranges, elevation), rtol=0, atol=1e-5)


def test_bogoslavskyi_beta_is_the_angle_at_the_far_point():
    # d_max = 2, d_min = 1, alpha = 60 deg: the triangle is right-angled at the near point, so the
    # angle at the far point is 30 deg.
    assert np.degrees(bogoslavskyi_beta(2.0, 1.0, np.radians(60.0))) == pytest.approx(30.0)
    assert np.degrees(bogoslavskyi_beta(1.0, 2.0, np.radians(60.0))) == pytest.approx(30.0)


def test_flic_wraps_around_horizontally():
    ranges = np.zeros((1, 8), np.float32)
    ranges[0, [0, 7]] = 10.0  # 2 columns apart across the seam: 10 m * 45 deg = far apart
    ranges[0, [0, 1, 6, 7]] = 1.0  # 1 m, 45 deg apart: chord 0.77 m < 0.8 m
    labels = flic_labels(ranges, np.zeros(1), 0.8, 1)
    assert labels[0, 0] == labels[0, 7] == labels[0, 1] == labels[0, 6] != 0
    assert labels.max() == 1


def test_map_connection_bridges_a_gap():
    # A flat wall at 5 m with one missing column: direct FLIC splits it, one MC (2, 2) joins it.
    w = 2048
    ranges = np.zeros((4, w), np.float32)
    ranges[:, 100:140] = 5.0
    ranges[:, 121] = 0.0
    elevation = np.radians([0.0, -0.4, -0.8, -1.2])
    direct = flic_labels(ranges, elevation, 0.8, 1)
    assert direct.max() == 2
    # the map of every 2nd column holds columns 120 and 122, which are 0.6 deg apart
    one_mc = flic_labels(ranges, elevation, 0.8, 1, maps=((2, 2),))
    assert one_mc.max() == 1
    # with the gap on column 120 the map itself has a hole; the neighbour reading still bridges it
    ranges[:, 121] = 5.0
    ranges[:, 120] = 0.0
    assert flic_labels(ranges, elevation, 0.8, 1, maps=((2, 2),)).max() == 2
    assert flic_labels(ranges, elevation, 0.8, 1, maps=((2, 2),), mc_mode="neighbour").max() == 1


def test_min_size_drops_small_clusters():
    ranges = np.zeros((2, 2048), np.float32)
    ranges[:, 0:3] = 4.0  # 6 pixels
    ranges[0, 6:8] = 4.0  # 2 pixels
    labels = flic_labels(ranges, np.radians([0.0, -0.4]), 0.8, min_size=3)
    assert labels.max() == 1 and (labels > 0).sum() == 6


def test_dbscan_labels_two_blobs_and_min_size():
    rng = np.random.default_rng(0)
    a = rng.normal([0, 0, 0], 0.05, (150, 3))
    b = rng.normal([5, 0, 0], 0.05, (120, 3))
    c = rng.normal([0, 9, 0], 0.05, (20, 3))  # too small
    labels = dbscan_labels(np.vstack([a, b, c]), eps_m=0.3, min_samples=5, min_size=100)
    assert set(labels[:150]) == {1} and set(labels[150:270]) == {2} and set(labels[270:]) == {0}


def test_drop_small_relabels_in_order_of_appearance():
    out = drop_small(np.array([5, 5, 0, 3, 3, 3, 9, -1]), 2)
    np.testing.assert_array_equal(out, [1, 1, 0, 2, 2, 2, 0, 0])


def test_flic_backends_agree_on_a_real_sized_scan(small_sample):
    import dataclasses

    from flic_cli.config import load_config
    from flic_cli.ground import PaperGround
    from flic_cli.io import open_dataset

    ds = open_dataset(small_sample.moosmann_log)
    frame = ds.load(ds.refs()[0])
    ground = PaperGround().extract(frame.image, frame.points)
    cfg = load_config()
    for name in ("flic0", "flic14"):
        method = cfg.method(name).method
        fast = method.segment(frame.image, frame.points, ground)
        scipy = dataclasses.replace(method, backend="scipy")
        ref = scipy.segment(frame.image, frame.points, ground)
        np.testing.assert_array_equal(fast, ref)
        assert fast.max() > 10


def test_unknown_backend_is_refused(tmp_path):
    from flic_cli.config import load_config
    from flic_cli.errors import FlicInputError

    path = tmp_path / "bad.toml"
    path.write_text('[methods.flic0]\nbackend = "cuda"\n')
    with pytest.raises(
        FlicInputError,
        match=r"bad.toml: \[methods.flic0\] backend: Input should be 'numba' or 'scipy'",
    ):
        load_config(path)


@settings(max_examples=100, deadline=None)
@given(image=range_images(), threshold=st.floats(0.3, 3.0), min_size=st.integers(1, 6))
def test_unit_weights_count_pixels(image, threshold, min_size):
    ranges, elevation = image
    ones = np.ones(ranges.shape, np.int32)
    by_pixels = flic_labels(ranges, elevation, threshold, min_size)
    np.testing.assert_array_equal(
        flic_labels(ranges, elevation, threshold, min_size, weights=ones), by_pixels
    )
    np.testing.assert_array_equal(
        bogoslavskyi_labels(ranges, elevation, 10.0, min_size, weights=ones),
        bogoslavskyi_labels(ranges, elevation, 10.0, min_size),
    )


def test_point_counts_of_a_projection_and_of_a_sensor_image():
    from flic_cli.projection import project_points
    from flic_cli.range_image import from_sensor_image

    # three points in one pixel (same direction, 5.0 / 5.1 / 5.2 m), one alone, 64 rings faked
    # by a spherical projection: the pixel holding three points counts 3
    d = np.array([[1.0, 0.0, 0.0]] * 3 + [[0.0, 1.0, 0.0]])
    pts = d * np.array([5.0, 5.1, 5.2, 7.0])[:, None]
    img = project_points(pts, width=16, mode="spherical", rows=4, fov_up_deg=5, fov_down_deg=-5)
    counts = img.point_counts()
    assert counts.sum() == 4 and sorted(counts[counts > 0].tolist()) == [1, 3]
    assert counts.reshape(-1)[img.point_pixel[0]] == 3
    np.testing.assert_array_equal(counts > 0, img.ranges > 0)
    ranges = np.zeros((2, 5), np.float32)
    ranges[0, 1] = ranges[1, 4] = 3.0
    native = from_sensor_image(ranges, np.zeros(2))
    np.testing.assert_array_equal(native.point_counts(), (ranges > 0).astype(np.int32))


def test_min_size_counts_points_not_pixels():
    # 60 pixels of a wall holding two points each: 120 points, kept at min_size 100
    from flic_cli.methods import Bogoslavskyi, Flic
    from flic_cli.range_image import RangeImage

    ranges = np.zeros((2, 2048), np.float32)
    ranges[:, 100:130] = 6.0
    pix = np.repeat(np.flatnonzero(ranges.reshape(-1) > 0), 2)
    img = RangeImage(ranges, np.radians([0.0, -0.4]), pix, "rings")
    for method in (Flic(), Flic(backend="scipy"), Bogoslavskyi()):
        labels = method.segment(img, np.zeros((pix.size, 3), np.float32), None)
        assert labels.shape == (120,) and (labels == 1).all(), method
    assert (Flic(min_size=121).segment(img, np.zeros((120, 3), np.float32), None) == 0).all()


def test_drop_small_with_weights():
    out = drop_small(np.array([5, 5, 0, 3, 3, 9]), 3, weights=np.array([1, 1, 7, 1, 1, 3]))
    np.testing.assert_array_equal(out, [0, 0, 0, 0, 0, 1])


def test_dbscan_backends_agree_on_a_random_cloud():
    pytest.importorskip(
        "dbscan", reason="the fastdbscan backend needs pip install 'flic[fastdbscan]'"
    )
    from flic_cli.methods.dbscan import raw_dbscan

    # blobs of different density plus uniform noise; coordinates on a 1/1024 m grid shifted by
    # 1/2048 m, so that no two points are exactly eps apart (where the backends may differ)
    rng = np.random.default_rng(1)
    centres = rng.uniform(-20, 20, (12, 3))
    blobs = [rng.normal(c, rng.uniform(0.1, 0.4), (rng.integers(20, 300), 3)) for c in centres]
    pts = np.vstack([*blobs, rng.uniform(-25, 25, (400, 3))])
    pts = np.round(pts * 1024) / 1024 + 1 / 2048
    ref_raw, ref_core = raw_dbscan(pts, 0.5, 5, "sklearn")
    raw, core = raw_dbscan(pts, 0.5, 5, "fastdbscan")
    np.testing.assert_array_equal(core, ref_core)
    # core points: the same partition; a border point may join any cluster it touches
    from sklearn.metrics import adjusted_rand_score

    assert adjusted_rand_score(ref_raw[ref_core], raw[core]) == 1.0
    np.testing.assert_array_equal(raw < 0, ref_raw < 0)
    ref = dbscan_labels(pts, 0.5, 5, 50)
    fast = dbscan_labels(pts, 0.5, 5, 50, backend="fastdbscan")
    assert ref.max() >= 5 and adjusted_rand_score(ref, fast) > 0.99


def test_dbscan_backend_is_validated():
    from flic_cli.methods import Dbscan

    with pytest.raises(ValueError, match="backend"):
        Dbscan(backend="cuda")


# ---- the reworked kernel against the previous one (tests/reference_kernels.py) ---------------


@settings(max_examples=300, deadline=None)
@given(
    image=range_images(),
    threshold=st.floats(0.3, 3.0),
    angle=st.floats(2.0, 60.0),
    maps=maps_strategy,
    mc_mode=st.sampled_from(["map", "neighbour"]),
    min_size=st.integers(1, 12),
    data=st.data(),
)
def test_kernel_gives_the_labels_of_the_previous_kernel(
    image, threshold, angle, maps, mc_mode, min_size, data
):
    ranges, elevation = image
    weights = data.draw(pixel_weights(ranges.shape))
    seed = data.draw(st.integers(0, 2**32 - 1))
    mask = data.draw(st.sampled_from([None, "ground"]))
    if mask == "ground":  # a ground-like mask: some pixels with a range left out
        mask = np.random.default_rng(seed).random(ranges.shape) > 0.3
    nodes = ranges > 0 if mask is None else mask & (ranges > 0)
    maps = tuple(m[:2] if m[2] == m[3] == 0 else m for m in maps)
    np.testing.assert_array_equal(
        flic_labels(ranges, elevation, threshold, min_size, maps, mc_mode, mask, weights),
        reference_kernels.flic_labels(
            ranges, elevation, threshold, min_size, maps, mc_mode, nodes, weights
        ),
    )
    np.testing.assert_array_equal(
        bogoslavskyi_labels(ranges, elevation, angle, min_size, mask, weights),
        reference_kernels.bogoslavskyi_labels(ranges, elevation, angle, min_size, nodes, weights),
    )


REFERENCE_METHODS = (
    "bogoslavskyi", "flic0", "flic1", "flic6", "flic14", "flic1n", "flic6n", "flic14n", "bridge",
)  # fmt: skip


def _same_labels_as_before(data: Path, methods, settings_, frames=None) -> int:
    """Compare every method's segment() with the previous kernels on the frames of ``data``,
    on the pipeline's image and mask (ground and held cells left out) without the attachment of
    held cells, which the previous kernels did not have (tests/test_ground_column.py tests it);
    returns the number of comparisons. Bridge is compared without its limit on open holes and
    without its level rule, which the previous kernel did not have (tests/test_bridge.py checks
    both against the brute-force graph)."""
    import dataclasses

    from flic_cli.config import load_config
    from flic_cli.ground.base import Ground
    from flic_cli.io import open_dataset
    from flic_cli.methods import Bridge
    from flic_cli.runs.pipeline import build_segmenter, prepare

    cfg = load_config()
    ds = open_dataset(data)
    done = 0
    for setting, remover in settings_:
        segs = [build_segmenter(cfg, name, setting, remover) for name in methods]
        for ref in ds.refs()[:frames]:
            prep = prepare(ds.load(ref), setting, cfg.projection)
            for seg in segs:
                step = seg.ground_step(prep.image, prep.points)
                image, ground, mask = prep.image, None, None
                if step is not None:  # without the held cells' attachments
                    image, mask = step.image, step.left_out
                    ground = Ground.from_mask(image, mask)
                method = seg.method
                if isinstance(method, Bridge):
                    method = dataclasses.replace(method, open_holes_px=None, level_tolerance=0.0)
                got = method.segment(image, prep.points, ground)
                want = reference_kernels.segment(method, image, mask)
                np.testing.assert_array_equal(got, want, err_msg=f"{seg.name} {setting} {ref}")
                done += 1
    return done


def test_segment_gives_the_labels_of_the_previous_kernel_on_the_sample(small_sample):
    for data in (small_sample.moosmann_log, small_sample.kitti_root):
        settings_ = [("ground", "paper"), ("ground", "own")]
        if data == small_sample.kitti_root:
            settings_.append(("no-ground", "paper"))
        assert _same_labels_as_before(data, REFERENCE_METHODS, settings_) > 0


@pytest.mark.slow
def test_segment_gives_the_labels_of_the_previous_kernel_on_the_shared_frames(kitti_root):
    methods = ("bogoslavskyi", "flic0", "flic1", "flic14", "bridge")
    settings_ = [("ground", "paper"), ("ground", "own"), ("no-ground", "paper")]
    assert _same_labels_as_before(kitti_root, methods, settings_) == 50 * 5 * 3
    # the neighbour reading (slower) on a few frames
    assert _same_labels_as_before(kitti_root, ("flic14n",), settings_[:1], frames=5) == 5


def test_the_shipped_example_config_loads_and_its_map_offsets_are_used():
    # configs/example.toml is what docs/cli.md points users to; a map with an offset of 0 was
    # once refused there (offsets were validated as steps)
    from pathlib import Path

    from flic_cli.config import load_config
    from flic_cli.methods.flic import connection_sets

    example = Path(__file__).resolve().parents[1] / "configs" / "example.toml"
    mine = load_config(example).method("mine").method
    assert mine.maps == ((3, 1), (1, 3, 0, 1)) and mine.threshold_m == 0.6
    steps, offsets, _ = connection_sets(mine.maps, mine.mc_mode)
    assert steps.tolist() == [[1, 1], [3, 1], [1, 3]]
    assert offsets.tolist() == [[0, 0], [0, 0], [0, 1]]
