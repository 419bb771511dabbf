"""Tests of flic_cli.plots: every picture is a valid PNG written atomically; the marks of the
frame views agree with the evaluation protocol."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import lab
from PIL import Image

from flic_cli.metrics import segmentation_stats
from flic_cli.plots import (
    object_marks,
    plot_hz_boxplot,
    plot_quality_speed,
    plot_runtime_histogram,
    render_frame_views,
    render_segmentation,
)
from flic_cli.projection import project_points

CAR, ROAD, BUILDING = 10, 40, 50


def assert_png(path: Path) -> tuple[int, int]:
    """The file is a decodable PNG and nothing else was left in its folder."""
    with Image.open(path) as img:
        img.load()
        assert img.format == "PNG"
        size = img.size
    assert size[0] > 100 and size[1] > 100
    assert [p.name for p in path.parent.iterdir()] == [path.name]
    return size


def scene() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points, ground-truth labels and a prediction: car 1 found, car 2 split, cars 3 and 4
    merged into one cluster, car 5 missed, a building clustered, road unclustered."""
    rng = np.random.default_rng(0)

    def blob(cx, cy, n, z=0.5):
        return np.c_[rng.normal(cx, 0.6, n), rng.normal(cy, 0.6, n), rng.normal(z, 0.3, n)]

    parts = [
        (blob(8, 2, 150), lab(CAR, 1), 1),
        (blob(-6, 5, 80), lab(CAR, 2), 2),
        (blob(-6, 6.5, 80), lab(CAR, 2), 3),
        (blob(12, -4, 120), lab(CAR, 3), 4),
        (blob(13, -5, 120), lab(CAR, 4), 4),
        (blob(-15, -10, 130), lab(CAR, 5), 0),
        (blob(20, 15, 400, 3), lab(BUILDING), 5),
        (np.c_[rng.uniform(-30, 30, (3000, 2)), np.full(3000, -1.7)], lab(ROAD), 0),
    ]
    pts = np.vstack([p[0] for p in parts]).astype(np.float32)
    gt = np.concatenate([np.full(len(p[0]), p[1]) for p in parts]).astype(np.uint32)
    pred = np.concatenate([np.full(len(p[0]), p[2]) for p in parts])
    return pts, gt, pred


def test_object_marks_on_a_hand_built_scene() -> None:
    _, gt, pred = scene()
    m = object_marks(gt, pred)
    assert len(m.matches) == 5
    # cars 3 and 4 tie for cluster 4 (IoU 1/2 each): the lower label keeps it, car 4 is missed
    assert m.missed.tolist() == [lab(CAR, 4), lab(CAR, 5)]
    assert m.split.tolist() == [lab(CAR, 2)]  # 80 + 80 points in clusters 2 and 3
    assert m.merged.tolist() == [4]


@pytest.mark.slow
def test_frame_views_with_and_without_labels(tmp_path) -> None:
    pts, gt, pred = scene()
    ground = gt == lab(ROAD)
    counts = render_frame_views(
        tmp_path / "a" / "views.png", pts, pred, gt, ground, title="scene", extent_m=30
    )
    assert counts == {"clusters": 5, "objects": 5, "missed": 2, "split": 1, "merged": 1}
    w, h = assert_png(tmp_path / "a" / "views.png")
    assert w > h * 0.8  # two columns: ground truth beside the prediction
    counts = render_frame_views(tmp_path / "b" / "views.png", pts, pred)
    assert counts == {"clusters": 5}
    assert_png(tmp_path / "b" / "views.png")
    with pytest.raises(ValueError, match="pred"):
        render_frame_views(tmp_path / "c.png", pts, pred[:3])


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(0, 4), st.integers(0, 4), st.integers(1, 40)), min_size=1, max_size=12
    )
)
def test_object_marks_agree_with_segmentation_stats(runs) -> None:
    gt = np.repeat([lab(CAR, o) if o else lab(ROAD) for o, _, _ in runs], [n for *_, n in runs])
    pred = np.repeat([c for _, c, _ in runs], [n for *_, n in runs])
    m = object_marks(gt.astype(np.uint32), pred, min_points=20, min_fragment_points=5)
    s = segmentation_stats(gt.astype(np.uint32), pred, min_points=20, min_fragment_points=5)
    assert len(m.split) == s["over_segmented"]
    assert len(m.merged) == s["under_segmented"]
    assert len(m.matches) == s["objects"]
    assert set(m.missed.tolist()) == set(m.matches.label[m.matches.iou == 0].tolist())


@pytest.mark.slow
def test_range_image_render_has_a_legend_that_matches(tmp_path) -> None:
    pts, gt, pred = scene()
    image = project_points(pts, width=256, mode="spherical")
    ground = np.zeros(image.shape, dtype=bool)
    ground[-5:] = True
    render_segmentation(image, pred, ground, tmp_path / "r" / "range.png")
    assert_png(tmp_path / "r" / "range.png")
    render_segmentation(image, pred, None, tmp_path / "s" / "range.png", title="no ground")
    assert_png(tmp_path / "s" / "range.png")


@pytest.mark.slow
def test_benchmark_pictures(tmp_path) -> None:
    rng = np.random.default_rng(1)
    hz = {"flic0": 600 + 50 * rng.standard_normal(30), "dbscan": 2 + rng.random(4)}
    plot_hz_boxplot(hz, tmp_path / "b" / "box.png", title="frame rate")
    assert_png(tmp_path / "b" / "box.png")
    edges = np.logspace(-2, 5, 71)
    counts = {m: np.histogram(1000 / v, edges)[0] for m, v in hz.items()}
    plot_runtime_histogram(counts, edges, tmp_path / "h" / "hist.png", title="runtimes")
    w, h = assert_png(tmp_path / "h" / "hist.png")
    plot_runtime_histogram(
        {**counts, "flic14": counts["flic0"]}, edges, tmp_path / "h3" / "hist.png"
    )
    assert assert_png(tmp_path / "h3" / "hist.png")[1] > h  # one panel per method


@pytest.mark.slow
def test_quality_speed(tmp_path) -> None:
    names = ["flic0", "flic14", "dbscan"]
    ms = np.array([1.0, 1.6, 450.0])
    iou = np.array([70.8, 77.3, 86.4])
    plot_quality_speed(names, ms, iou, tmp_path / "q" / "qs.png", iou - 4, iou + 4, title="t")
    assert_png(tmp_path / "q" / "qs.png")
    low = np.array([np.nan, 73.0, 83.0])
    plot_quality_speed(names, ms, iou, tmp_path / "r" / "qs.png", low, iou + 3)
    assert_png(tmp_path / "r" / "qs.png")
    plot_quality_speed(names, ms, iou, tmp_path / "s" / "qs.png")
    assert_png(tmp_path / "s" / "qs.png")
    with pytest.raises(ValueError, match="> 0"):
        plot_quality_speed(names, ms * 0, iou, tmp_path / "x.png")
    with pytest.raises(ValueError, match="one entry"):
        plot_quality_speed(names[:2], ms, iou, tmp_path / "x.png")
