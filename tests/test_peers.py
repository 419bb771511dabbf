"""The field's clusterers (issue 23) against brute-force definitions on small random inputs."""

from __future__ import annotations

import numpy as np
import pytest
from oracles import graph_components, same_partition

from flic_cli.errors import FlicInputError
from flic_cli.ground.base import Ground
from flic_cli.methods.alpine import Alpine, box_extent, split_cluster
from flic_cli.methods.cvc import Cvc, curved_voxels, voxel_components
from flic_cli.methods.euclidean import CELL_SHRINK, Euclidean, radius_components
from flic_cli.methods.hdbscan import Hdbscan
from flic_cli.methods.slr import Slr, slr_pixels
from flic_cli.range_image import RangeImage
from flic_cli.runs.pipeline import needs_semantics, segment_with


def sensor_image(points: np.ndarray) -> RangeImage:
    """A one-row-per-point image whose pixels are the points (for the 3D methods' plumbing)."""
    n = points.shape[0]
    return RangeImage(
        np.ones((1, n), dtype=np.float32), np.zeros(1), np.arange(n, dtype=np.int64), "native"
    )


# ---- Euclidean -----------------------------------------------------------------------------


def brute_radius(pts: np.ndarray, r: float) -> np.ndarray:
    """Components of the graph of every pair strictly closer than ``r`` (all pairs computed)."""
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    i, j = np.nonzero(d < r)
    return graph_components(len(pts), list(zip(i.tolist(), j.tolist(), strict=True)))


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("r", [0.15, 0.6, 1.7])
def test_euclidean_is_the_radius_graph(seed: int, r: float) -> None:
    rng = np.random.default_rng(seed)
    pts = rng.uniform(0, 4, size=(160, 3))
    pts[100:120] = pts[:20]  # coinciding points
    pts[120:] = rng.normal(2.0, 0.03, size=(40, 3))  # a dense blob: many pairs per cell
    assert same_partition(radius_components(pts, r), brute_radius(pts, r))


def test_euclidean_links_only_pairs_closer_than_the_tolerance() -> None:
    # a lattice of spacing exactly 0.5 m (exact in binary): PCL does not link pairs at exactly
    # the tolerance (FLANN keeps dist < radius); the diagonals are 0.71 m
    g = np.arange(4) * 0.5
    pts = np.stack(np.meshgrid(g, g, g), axis=-1).reshape(-1, 3)
    assert np.unique(radius_components(pts, 0.5)).size == pts.shape[0]
    assert np.unique(radius_components(pts, 0.5 + 1e-9)).size == 1
    # pairs just under the tolerance in random directions: their cells are up to 2 apart per axis
    rng = np.random.default_rng(0)
    u = rng.normal(size=(300, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    p = rng.uniform(0, 1, size=(300, 3)) + 10.0 * np.arange(300)[:, None]
    pts = np.vstack([p, p + 0.5 * (1 - 1e-6) * u])
    assert same_partition(radius_components(pts, 0.5), np.tile(np.arange(300), 2))
    # the farthest candidate cell offset, (2, 2, 2): p just under its cell's far corner
    # (the grid starts at the smallest coordinate, 0 here), q in the cell two further on
    side = 0.5 / np.sqrt(3) * (1 - CELL_SHRINK)
    p = np.full(3, side * (1 - 1e-11))
    q = p + 0.5 * (1 - 1e-12) / np.sqrt(3)
    assert (np.floor(q / side) - np.floor(p / side) == 2).all()
    pts = np.vstack([np.zeros(3), p, q])
    assert same_partition(radius_components(pts, 0.5), brute_radius(pts, 0.5))
    assert np.unique(radius_components(pts, 0.5)[1:]).size == 1


def test_euclidean_method_drops_small_and_ground() -> None:
    rng = np.random.default_rng(1)
    blob = rng.normal(0, 0.05, size=(30, 3))
    far = rng.normal(10, 0.05, size=(5, 3))
    pts = np.vstack([blob, far]).astype(np.float32)
    img = sensor_image(pts)
    labels = Euclidean(tolerance_m=0.5, min_size=10).segment(img, pts, None)
    assert (labels[:30] == 1).all() and (labels[30:] == 0).all()
    mask = np.zeros((1, 35), dtype=bool)
    mask[0, :25] = True  # leaves 5 blob points: under the minimum
    labels = Euclidean(tolerance_m=0.5, min_size=5).segment(img, pts, Ground.from_mask(img, mask))
    assert (labels[:25] == 0).all() and (labels[25:30] == 1).all() and (labels[30:] == 2).all()
    labels = Euclidean(tolerance_m=0.5, min_size=5, max_size=29).segment(img, pts, None)
    assert (labels[:30] == 0).all() and (labels[30:] == 1).all()  # PCL's setMaxClusterSize


# ---- CVC -----------------------------------------------------------------------------------


def brute_cvc(pts: np.ndarray, dr: float, dp: float, da: float) -> np.ndarray:
    """Voxels computed point by point with math, linked when every index differs by <= 1."""
    import math

    rng = [math.sqrt(x * x + y * y + z * z) for x, y, z in pts]
    pol = [math.acos(z / r) for (_, _, z), r in zip(pts, rng, strict=True)]
    az = [math.atan2(y, x) for x, y, _ in pts]
    n_az = math.ceil(2 * math.pi / math.radians(da))
    cells = [
        (
            math.floor((r - min(rng)) / dr),
            math.floor((p - min(pol)) / math.radians(dp)),
            math.floor((a + math.pi) / math.radians(da)) % n_az,
        )
        for r, p, a in zip(rng, pol, az, strict=True)
    ]
    edges = []
    for i, ci in enumerate(cells):
        for j, cj in enumerate(cells):
            da_ = abs(ci[2] - cj[2])
            if abs(ci[0] - cj[0]) <= 1 and abs(ci[1] - cj[1]) <= 1 and min(da_, n_az - da_) <= 1:
                edges.append((i, j))
    return graph_components(len(pts), edges)


@pytest.mark.parametrize("seed", range(6))
def test_cvc_is_the_curved_voxel_graph(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 150
    r = rng.uniform(2, 12, n)
    az = rng.uniform(-np.pi, np.pi, n)
    el = rng.uniform(-0.3, 0.1, n)
    pts = np.stack([r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el)], 1)
    cvc = Cvc(delta_range_m=1.5, delta_polar_deg=6.0, delta_azimuth_deg=20.0)
    got = cvc.raw(pts)
    assert same_partition(got, brute_cvc(pts, 1.5, 6.0, 20.0))


def test_cvc_azimuth_wraps_round() -> None:
    # two points either side of the -180/180 deg seam, in the same range and polar bin
    pts = np.array([[-5.0, 0.01, 0.0], [-5.0, -0.01, 0.0]])
    cells, n_az = curved_voxels(pts, 0.5, 3.0, 1.3)
    assert {int(cells[0, 2]), int(cells[1, 2])} == {0, n_az - 1}
    assert voxel_components(cells, n_az).tolist() == [0, 0]


# ---- SLR -----------------------------------------------------------------------------------


def row_image(ranges: np.ndarray, elevation_deg: np.ndarray) -> RangeImage:
    h, w = ranges.shape
    return RangeImage(
        ranges.astype(np.float32), np.radians(elevation_deg).astype(np.float64),
        np.flatnonzero(ranges.reshape(-1) > 0).astype(np.int64), "native",
    )  # fmt: skip


def brute_slr(img: RangeImage, valid: np.ndarray, run_m: float, merge_m: float) -> np.ndarray:
    """The paper's graph: consecutive measurements of a line (cyclic) closer than ``run_m``;
    each measurement to its nearest measurement in the line above if closer than ``merge_m``."""
    h, w = valid.shape
    xyz = img.to_points().astype(np.float64).reshape(h, w, 3)
    edges = [(int(i), int(i)) for i in np.flatnonzero(valid)]
    for r in range(h):
        cols = np.flatnonzero(valid[r])
        for a, b in zip(cols, np.roll(cols, -1), strict=True):
            if a != b and np.linalg.norm(xyz[r, a] - xyz[r, b]) < run_m:
                edges.append((r * w + a, r * w + b))
        if r == 0:
            continue
        above = np.flatnonzero(valid[r - 1])
        for c in cols:
            if above.size:
                d = np.linalg.norm(xyz[r - 1, above] - xyz[r, c], axis=1)
                if d.min() < merge_m:
                    edges.append((r * w + c, (r - 1) * w + above[np.argmin(d)]))
    comp = graph_components(h * w, edges)
    return comp[valid.reshape(-1)]


@pytest.mark.parametrize("seed", range(8))
def test_slr_is_the_scan_line_graph(seed: int) -> None:
    rng = np.random.default_rng(seed)
    h, w = 6, 40
    ranges = rng.choice([2.0, 2.3, 6.0, 6.4, 15.0], size=(h, w)) + rng.normal(0, 0.05, (h, w))
    ranges[rng.random((h, w)) < 0.3] = 0
    img = row_image(ranges, np.linspace(2, -15, h))
    valid = ranges > 0
    got = slr_pixels(img, valid, 0.5, 1.0)[valid.reshape(-1)]
    assert same_partition(got, brute_slr(img, valid, 0.5, 1.0))


def test_slr_runs_on_a_hand_built_line() -> None:
    # one line: 3 measurements at 5 m, a jump to 9 m, 3 more, then back to 5 m before the seam
    w = 360
    ranges = np.zeros((1, w))
    ranges[0, [0, 1, 2]] = 5.0
    ranges[0, [3, 4, 5]] = 9.0
    ranges[0, [358, 359]] = 5.0  # closes round to the first run
    img = row_image(ranges, np.array([0.0]))
    lab = slr_pixels(img, ranges > 0, 0.5, 1.0).reshape(ranges.shape)[0]
    assert lab[0] == lab[1] == lab[2] == lab[358] == lab[359]
    assert lab[3] == lab[4] == lab[5] != lab[0]
    # a second line below the 9 m run merges with it, not with the 5 m run
    ranges2 = np.zeros((2, w))
    ranges2[0] = ranges[0]
    ranges2[1, [3, 4]] = 9.0
    img2 = row_image(ranges2, np.array([0.0, -2.0]))
    lab2 = slr_pixels(img2, ranges2 > 0, 0.5, 1.0).reshape(ranges2.shape)
    assert lab2[1, 3] == lab2[1, 4] == lab2[0, 4] != lab2[0, 0]


def test_slr_method_counts_points_and_drops_small() -> None:
    ranges = np.zeros((2, 100))
    ranges[:, 10:20] = 5.0
    img = row_image(ranges, np.array([0.0, -1.0]))
    pts = img.to_points()[img.point_pixel]
    assert (Slr(min_size=20).segment(img, pts, None) == 1).all()
    assert (Slr(min_size=21).segment(img, pts, None) == 0).all()


# ---- ALPINE --------------------------------------------------------------------------------


def brute_knn_components(xy: np.ndarray, link: float, k: int) -> np.ndarray:
    n = xy.shape[0]
    d = np.linalg.norm(xy[:, None] - xy[None], axis=2)
    edges = [(i, i) for i in range(n)]
    for i in range(n):
        order = [j for j in np.argsort(d[i], kind="stable") if j != i][: min(k, n - 1)]
        edges += [(i, int(j)) for j in order if d[i, j] < link]
    return graph_components(n, edges)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("k", [1, 3, 8])
def test_alpine_is_the_per_class_knn_graph(seed: int, k: int) -> None:
    rng = np.random.default_rng(seed)
    n = 90
    pts = rng.uniform(0, 8, size=(n, 3))
    classes = rng.choice([1, 6, 13], size=n)  # car, person, and a stuff class (building)
    got = Alpine(k=k, split=False, min_size=1).raw(pts, classes)
    assert (got[classes == 13] == 0).all()
    for cls, width in ((1, 1.8), (6, 0.94)):
        sel = classes == cls
        assert same_partition(got[sel], brute_knn_components(pts[sel, :2], width, k))
    # no cluster spans two classes
    assert not set(got[classes == 1]) & set(got[classes == 6])


def test_alpine_box_extent_of_a_rotated_rectangle() -> None:
    rng = np.random.default_rng(0)
    u = rng.uniform(0, 4.0, 400)
    v = rng.uniform(0, 1.5, 400)
    corners = np.array([[0, 0], [4.0, 0], [4.0, 1.5], [0, 1.5]])
    uv = np.vstack([corners, np.stack([u, v], 1)])
    t = np.radians(33.0)
    xy = uv @ np.array([[np.cos(t), np.sin(t)], [-np.sin(t), np.cos(t)]])
    a, b = box_extent(xy)
    assert sorted([a, b]) == pytest.approx([1.5, 4.0], abs=1e-9)


def test_alpine_splits_two_cars_in_a_row() -> None:
    # two 4 m cars 1 m apart along x: one cluster at the car's 1.8 m link, 9 m long
    rng = np.random.default_rng(3)
    car = np.stack([rng.uniform(0, 4, 300), rng.uniform(0, 1.7, 300)], 1)
    xy = np.vstack([car, car + [5.0, 0.0]])
    n, parts = split_cluster(xy, 1.8, (4.4, 1.8), 1.3, 8)
    assert n == 2
    assert same_partition(parts, np.repeat([0, 1], 300))
    # one car fits its box: not split
    assert split_cluster(car, 1.8, (4.4, 1.8), 1.3, 8)[0] == 1


def test_alpine_needs_semantics_unless_agnostic() -> None:
    pts = np.zeros((3, 3), dtype=np.float32)
    img = sensor_image(pts)
    assert needs_semantics(Alpine()) and not needs_semantics(Alpine(agnostic=True))
    with pytest.raises(FlicInputError):
        Alpine().segment(img, pts, None)
    assert segment_with(Alpine(min_size=1), img, pts, None, np.array([10, 10, 50])).tolist() == [
        1, 1, 0,
    ]  # fmt: skip
    assert (Alpine(agnostic=True, min_size=3).segment(img, pts, None) == 1).all()


# ---- HDBSCAN -------------------------------------------------------------------------------


def test_hdbscan_separates_blobs_and_leaves_noise() -> None:
    rng = np.random.default_rng(0)
    a = rng.normal(0, 0.1, (60, 3))
    b = rng.normal(5, 0.1, (60, 3))
    noise = np.array([[20.0, 20.0, 20.0]])
    pts = np.vstack([a, b, noise]).astype(np.float32)
    labels = Hdbscan(min_cluster_size=10, min_size=10).segment(sensor_image(pts), pts, None)
    assert len(set(labels[:60])) == 1 and len(set(labels[60:120])) == 1
    assert labels[0] != labels[60] and labels[0] > 0 and labels[60] > 0 and labels[120] == 0


# ---- the runs ------------------------------------------------------------------------------


@pytest.mark.slow
def test_evaluate_runs_every_new_method_with_oracle_semantics(
    sample_root,
    tmp_path,  # noqa: ANN001
) -> None:
    """`flic evaluate --semantics oracle` runs the new methods (ALPINE with the ground truth's
    classes) and writes OSE / USE and the oracle PQ with intervals."""
    import pandas as pd
    from typer.testing import CliRunner

    from flic_cli.cli import app

    out = tmp_path / "ev"
    methods = "euclidean,slr,cvc,alpine,alpine-agnostic"
    result = CliRunner().invoke(
        app,
        ["evaluate", str(sample_root), "--methods", methods, "--frames", "0:2",
         "--semantics", "oracle", "--out", str(out)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "OSE" in result.output and "PQ_oracle" in result.output
    table = pd.read_csv(out / "table.csv")
    assert table["method"].tolist() == methods.split(",")
    for col in ("ose", "use", "pq_oracle", "pq_things_oracle"):
        assert table[col].notna().all() and (table[col] >= 0).all()
    frames = pd.read_csv(out / "per_frame.csv")
    assert {"ose", "use"} <= set(frames.columns)
    # the table's OSE is the mean of the per-frame values of the P setting
    sel = frames[(frames["method"] == "slr") & (frames["setting"] == "no-ground")]
    assert table.set_index("method").loc["slr", "ose"] == pytest.approx(sel["ose"].mean(), abs=1e-4)


@pytest.mark.slow
def test_segment_needs_semantics_for_alpine(sample_root, tmp_path) -> None:  # noqa: ANN001
    from typer.testing import CliRunner

    from flic_cli.cli import app

    runner = CliRunner()
    base = ["segment", str(sample_root), "--method", "alpine", "--frames", "0:1"]
    bad = runner.invoke(app, [*base, "--out", str(tmp_path / "a")])
    assert bad.exit_code == 2 and "--semantics" in bad.output
    good = runner.invoke(app, [*base, "--semantics", "oracle", "--out", str(tmp_path / "b")])
    assert good.exit_code == 0, good.output


def test_default_methods_with_semantics_add_the_per_class_ones(tmp_path) -> None:  # noqa: ANN001
    """Without --methods, `evaluate --semantics oracle` runs `default_methods` and then
    `default_semantic_methods`; a config naming an unknown variant there is refused."""
    from flic_cli.config import load_config
    from flic_cli.runs.pipeline import parse_methods

    cfg = load_config(None)
    plain = parse_methods(None, cfg)
    with_sem = parse_methods(None, cfg, semantics=True)
    assert plain == list(cfg.default_methods) and "alpine" not in plain
    assert with_sem == plain + [m for m in cfg.default_semantic_methods if m not in plain]
    assert {"alpine", "alpine-k32"} <= set(with_sem)
    assert parse_methods("slr", cfg, semantics=True) == ["slr"]  # --methods wins
    own = tmp_path / "own.toml"
    own.write_text('default_semantic_methods = ["slr", "flic0-scipy"]\n')
    assert parse_methods(None, load_config(own), semantics=True) == [*plain, "flic0-scipy"]
    bad = tmp_path / "bad.toml"
    bad.write_text('default_semantic_methods = ["nothing"]\n')
    with pytest.raises(FlicInputError, match="default_semantic_methods"):
        load_config(bad)
