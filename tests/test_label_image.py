"""Tests of the Moosmann-log predictions as 16-bit PNG label images (flic_cli.io.moosmann)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from flic_cli.errors import FlicInputError
from flic_cli.io.moosmann import (
    ImgCfg,
    is_moosmann,
    label_image,
    label_image_path,
    read_label_image,
    write_img_cfg,
    write_label_image,
    write_png_range,
)

CFG = ImgCfg(16, 4, 180.0, -180.0, np.array([-2.0, 3.5, 9.0, 24.5]))


def test_path_is_named_after_the_range_image(tmp_path) -> None:
    assert label_image_path(tmp_path, "log1", "scan00012.png") == (
        tmp_path / "log1" / "scan00012.label.png"
    )
    assert label_image_path("out", "a", Path("/data/a/range/scan7.png")) == Path(
        "out/a/scan7.label.png"
    )


def test_round_trip_with_large_ids(tmp_path) -> None:
    rng = np.random.default_rng(0)
    labels = rng.integers(0, 65536, (4, 16))
    labels[0, :4] = [0, 255, 256, 65535]
    path = write_label_image(label_image_path(tmp_path, "log", "scan00003.png"), labels)
    got = read_label_image(path, CFG)
    assert got.dtype == np.int32
    np.testing.assert_array_equal(got, labels)
    with Image.open(path) as img:  # a plain 16-bit greyscale PNG for any image tool
        assert img.format == "PNG" and img.size == (16, 4) and img.mode.startswith("I;16")
    assert path.read_bytes()[24:26] == bytes([16, 0])  # IHDR: bit depth 16, greyscale
    assert sorted(p.name for p in path.parent.iterdir()) == ["scan00003.label.png"]


def test_ids_over_16_bits_are_refused(tmp_path) -> None:
    path = tmp_path / "scan1.label.png"
    with pytest.raises(ValueError, match="0..65535"):
        write_label_image(path, np.array([[1, 65536]]))
    with pytest.raises(ValueError, match="0..65535"):
        write_label_image(path, np.array([[-1, 2]]))
    with pytest.raises(ValueError, match="2-D integer"):
        write_label_image(path, np.zeros((2, 2), dtype=np.float32))
    assert not path.exists() and list(tmp_path.iterdir()) == []


def test_read_errors(tmp_path) -> None:
    small = write_label_image(tmp_path / "s.label.png", np.ones((4, 8), dtype=int))
    with pytest.raises(FlicInputError, match="is 8x4 but img.cfg says 16x4"):
        read_label_image(small, CFG)
    eight = tmp_path / "e.label.png"
    Image.fromarray(np.zeros((4, 16), dtype=np.uint8)).save(eight)
    with pytest.raises(FlicInputError, match="8-bit greyscale, expected 16-bit"):
        read_label_image(eight, CFG)
    with pytest.raises(FlicInputError, match="does not exist"):
        read_label_image(tmp_path / "missing.label.png", CFG)


def test_label_image_from_points() -> None:
    point_pixel = np.array([0, 5, 5, -1, 17, 63])
    labels = np.array([3, 300, 300, 9, -1, 2])
    img = label_image(point_pixel, labels, (4, 16))
    expected = np.zeros(64, dtype=np.int64)
    expected[[0, 5, 63]] = [3, 300, 2]
    np.testing.assert_array_equal(img.reshape(-1), expected)
    with pytest.raises(ValueError, match="differ"):
        label_image(point_pixel, labels[:2], (4, 16))


def test_output_folder_is_not_read_as_a_log(tmp_path) -> None:
    write_img_cfg(tmp_path / "log" / "img.cfg", CFG)
    write_png_range(tmp_path / "log" / "scan00001.png", np.ones((4, 16)))
    out = tmp_path / "out"
    write_label_image(label_image_path(out, "log", "scan00001.png"), np.ones((4, 16), int))
    assert is_moosmann(tmp_path / "log")
    assert not is_moosmann(out)
