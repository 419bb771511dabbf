"""`flic view --screenshot`: the PNG's colours against the labels (polyscope, EGL, no window).

Skipped where the `viewer` extra (polyscope) is missing or EGL cannot start."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

pytest.importorskip("polyscope")

from flic_cli.cli import app  # noqa: E402
from flic_cli.config import load_config  # noqa: E402
from flic_cli.errors import FlicInputError  # noqa: E402
from flic_cli.viewer import Viewer  # noqa: E402

NEBULA = "sensors/velodyne/nebula_vlp16/1673400471837873222"


def _viewer(data, methods, frames=None):
    try:
        viewer = Viewer(data, methods, frames, None, load_config(None))
        viewer.init(headless=True)
    except FlicInputError as exc:
        if "cannot render without a window" in str(exc):
            pytest.skip(str(exc))
        raise
    return viewer


def _pixels(path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB")).astype(np.int64)


def _palette(rgb: np.ndarray) -> np.ndarray:
    """The distinct colours as the renderer writes them (8 bits, truncated)."""
    return np.unique(np.floor(rgb * 255 + 1e-6).astype(np.int64), axis=0)


def _share_in(pixels: np.ndarray, palette: np.ndarray) -> float:
    """Share of the non-black pixels whose colour lies within 1 of a palette colour."""
    px = pixels.reshape(-1, 3)
    px = px[px.sum(axis=1) > 0]
    d = np.abs(px[:, None, :] - palette[None, :, :]).max(axis=2).min(axis=1)
    return float(np.mean(d <= 1))


def _count(pixels: np.ndarray, colour: np.ndarray) -> int:
    return int(np.count_nonzero((np.abs(pixels - colour) <= 1).all(axis=2)))


@pytest.mark.slow
def test_screenshot_colours_match_prediction_and_ground_truth(small_sample, tmp_path):
    viewer = _viewer(small_sample.kitti_root, ["flic14"], (0, 1))
    vf = viewer.screenshot(tmp_path / "shot.png")
    px = _pixels(tmp_path / "shot.png")
    h, w, _ = px.shape
    left, right = px[:, : w // 2], px[:, w // 2 :]
    pred, gt = _palette(vf.pred_rgb), _palette(vf.gt_rgb)
    # every drawn pixel has a colour of its side's labels
    assert _share_in(left, pred) > 0.99
    assert _share_in(right, gt) > 0.99
    # the largest clusters show on the left in their colour; a cluster that found no object
    # (its colour absent from the ground truth) does not show on the right
    colours, counts = np.unique(_palette_rows(vf.pred_rgb), axis=0, return_counts=True)
    gt_set = {tuple(c) for c in gt}
    checked = 0
    for colour in colours[np.argsort(-counts)][:8]:
        assert _count(left, colour) >= 20, colour
        if tuple(colour) not in gt_set:
            assert _count(right, colour) == 0, colour
            checked += 1
    # objects found by a cluster: the same colour on both sides
    shared = [c for c in colours[np.argsort(-counts)][:30] if tuple(c) in gt_set]
    assert shared and all(_count(right, c) >= 5 for c in shared[:5])
    assert vf.clusters > 20


def _palette_rows(rgb: np.ndarray) -> np.ndarray:
    return np.floor(rgb * 255 + 1e-6).astype(np.int64)


@pytest.mark.slow
def test_screenshot_switches_method_and_frame(small_sample, tmp_path):
    viewer = _viewer(small_sample.kitti_root, ["flic14", "bogoslavskyi"], (0, 2))
    a = viewer.screenshot(tmp_path / "a.png")
    viewer.method, viewer.index = "bogoslavskyi", 1
    b = viewer.screenshot(tmp_path / "b.png")
    assert "flic14" in a.title and "bogoslavskyi" in b.title and "frame 1" in b.title
    assert _share_in(_pixels(tmp_path / "b.png")[:, :800], _palette(b.pred_rgb)) > 0.99
    assert not np.array_equal(_pixels(tmp_path / "a.png"), _pixels(tmp_path / "b.png"))


@pytest.mark.slow
def test_screenshot_of_a_bag_without_labels(shared_data, tmp_path):
    viewer = _viewer(shared_data / NEBULA, ["flic14"], (3, 4))
    vf = viewer.screenshot(tmp_path / "bag.png")
    assert vf.gt_rgb is None
    px = _pixels(tmp_path / "bag.png")
    assert _share_in(px, _palette(vf.pred_rgb)) > 0.99
    assert np.count_nonzero(px.sum(axis=2)) > 2000


@pytest.mark.slow
def test_view_cli_screenshot(small_sample, tmp_path):
    _viewer(small_sample.kitti_root, ["flic14"], (0, 1))  # skips where EGL cannot start
    out = tmp_path / "cli.png"
    result = CliRunner().invoke(
        app,
        ["view", str(small_sample.kitti_root), "--frames", "0", "--method", "flic14",
         "--screenshot", str(out)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "flic14" in result.output and Image.open(out).format == "PNG"
