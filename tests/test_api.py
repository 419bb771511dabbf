"""The Python API (flic_cli.api): the same labels as the command line, and the README example
runs as written."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import flic_cli.api as flic
from flic_cli.cli import main
from flic_cli.io import open_dataset, read_predictions

README = Path(__file__).resolve().parents[1] / "README.md"


@pytest.mark.slow
def test_segment_points_equals_flic_segment(small_sample, tmp_path):
    with pytest.raises(SystemExit):
        main(
            ["segment", str(small_sample.kitti_root), "--method", "flic14", "--out", str(tmp_path)]
        )
    frame = flic.load_frame(small_sample.kitti_root, frame=1)
    labels = flic.segment_points(frame.points, method="flic14")
    np.testing.assert_array_equal(labels, read_predictions(tmp_path, "00", 1))
    assert labels.dtype == np.int32 and labels.max() > 10


@pytest.mark.slow
def test_run_takes_a_run_specification(small_sample, tmp_path):
    sel = flic.Selection(small_sample.kitti_root, frames=(1, 2), progress=False)
    summary = flic.run(flic.SegmentRun(sel, tmp_path / "seg", "flic14"))
    assert summary.frames == 1
    frame = flic.load_frame(small_sample.kitti_root, frame=1)
    np.testing.assert_array_equal(
        read_predictions(tmp_path / "seg", "00", 1), flic.segment_points(frame.points, "flic14")
    )
    with pytest.raises(TypeError, match="not a run specification"):
        flic.run(sel)


def test_segment_points_options(small_sample):
    frame = flic.load_frame(small_sample.kitti_root, frame=0)
    pts = np.concatenate([frame.points, np.ones((frame.points.shape[0], 1), np.float32)], axis=1)
    pts[5, 0] = np.nan
    labels = flic.segment_points(pts, method="flic0", ground=None)
    assert labels.shape == (pts.shape[0],) and labels[5] == 0
    # without ground extraction the road joins everything near it into fewer, bigger clusters
    with_ground = flic.segment_points(pts, method="flic0")
    assert np.count_nonzero(labels) > np.count_nonzero(with_ground)
    # not in scan order: a spherical projection, still one label per point
    order = np.random.default_rng(0).permutation(pts.shape[0])
    shuffled = flic.segment_points(pts[order], method="flic0", scan_order=False)
    assert shuffled.shape == (pts.shape[0],) and shuffled.max() > 10
    assert "flic14n" in flic.methods()


@pytest.mark.slow
def test_segment_range_image_equals_the_moosmann_prediction(small_sample, tmp_path):
    from flic_cli.io.moosmann import label_image_path, read_label_image

    with pytest.raises(SystemExit):
        main(
            ["segment", str(small_sample.moosmann_log), "--method", "flic6", "--out", str(tmp_path)]
        )
    ds = open_dataset(small_sample.moosmann_log)
    ref = ds.refs()[0]
    frame = ds.load(ref)
    got = flic.segment_range_image(frame.image.ranges, frame.image.elevation, method="flic6")
    expected = read_label_image(
        label_image_path(tmp_path, ref.sequence, ref.path), ds._cfg[ref.sequence]
    )
    np.testing.assert_array_equal(got, expected)


@pytest.mark.slow
def test_readme_example_runs():
    text = README.read_text(encoding="utf-8")
    section = text.split("## Python API", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert len(code.strip().splitlines()) <= 12
    namespace: dict = {}
    exec(compile(code, str(README), "exec"), namespace)  # noqa: S102 - our own README
    assert namespace["labels"].shape == (namespace["frame"].points.shape[0],)
