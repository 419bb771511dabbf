"""Tests of flic_cli.io.ply: the PLY export read back with plyfile and byte by byte."""

from __future__ import annotations

import numpy as np
import pytest
from plyfile import PlyData

from flic_cli.io.ply import GROUND_RGB, UNCLUSTERED_RGB, cluster_rgb, write_ply


def test_ply_round_trip_every_field(tmp_path) -> None:
    rng = np.random.default_rng(0)
    n = 1000
    points = rng.normal(0, 20, (n, 4)).astype(np.float64)  # 4th column (remission) ignored
    ids = rng.integers(-1, 300, n)
    ids[:5] = [0, 70000, 1, 1, -1]
    ground = np.zeros(n, dtype=bool)
    ground[10:50] = True
    path = write_ply(tmp_path / "sub" / "frame.ply", points, ids, ground)
    assert path == tmp_path / "sub" / "frame.ply"
    assert [p.name for p in (tmp_path / "sub").iterdir()] == ["frame.ply"]  # no temporary left

    ply = PlyData.read(str(path))
    assert not ply.text and ply.byte_order == "<"
    assert [e.name for e in ply.elements] == ["vertex"]
    v = ply["vertex"]
    assert [p.name for p in v.properties] == ["x", "y", "z", "cluster", "red", "green", "blue"]
    assert [p.val_dtype for p in v.properties] == ["f4"] * 3 + ["i4"] + ["u1"] * 3
    assert v.count == n
    for k, axis in enumerate("xyz"):
        np.testing.assert_array_equal(v[axis], points[:, k].astype(np.float32))
    np.testing.assert_array_equal(v["cluster"], np.maximum(ids, 0))
    rgb = np.stack([v["red"], v["green"], v["blue"]], axis=1)
    expected = cluster_rgb(np.maximum(ids, 0))
    expected[np.maximum(ids, 0) == 0] = UNCLUSTERED_RGB
    expected[ground] = GROUND_RGB
    np.testing.assert_array_equal(rgb, expected)
    assert tuple(rgb[0]) == UNCLUSTERED_RGB and tuple(rgb[4]) == UNCLUSTERED_RGB
    assert tuple(rgb[20]) == GROUND_RGB
    assert any("cluster id" in c for c in ply.comments)

    # The layout viewers rely on: an ASCII header, then 19 bytes per point, little-endian.
    data = path.read_bytes()
    header, body = data.split(b"end_header\n", 1)
    lines = header.decode("ascii").splitlines()
    assert lines[:2] == ["ply", "format binary_little_endian 1.0"]
    assert f"element vertex {n}" in lines
    assert [ln for ln in lines if ln.startswith("property")] == [
        "property float x",
        "property float y",
        "property float z",
        "property int cluster",
        "property uchar red",
        "property uchar green",
        "property uchar blue",
    ]
    assert len(body) == 19 * n
    first = np.frombuffer(body[:19], dtype="<f4", count=3)
    np.testing.assert_array_equal(first, points[0, :3].astype(np.float32))
    assert int.from_bytes(body[12:16], "little", signed=True) == 0
    assert int.from_bytes(body[19 + 12 : 19 + 16], "little", signed=True) == 70000


def test_cluster_colours_are_stable_and_distinct() -> None:
    ids = np.arange(1, 41)
    rgb = cluster_rgb(ids)
    assert rgb.dtype == np.uint8 and rgb.shape == (40, 3)
    np.testing.assert_array_equal(rgb, cluster_rgb(ids))  # same id, same colour, everywhere
    np.testing.assert_array_equal(cluster_rgb(np.array([7])), rgb[6:7])
    assert len({tuple(c) for c in rgb}) == 40
    # bright enough to stand out from both greys
    assert (rgb.max(axis=1) >= 200).all()
    # neighbouring ids far apart
    assert (np.abs(np.diff(rgb.astype(int), axis=0)).sum(axis=1) > 60).all()


def test_empty_frame_and_errors(tmp_path) -> None:
    path = write_ply(tmp_path / "empty.ply", np.zeros((0, 3)), np.zeros(0, dtype=int))
    assert PlyData.read(str(path))["vertex"].count == 0
    pts = np.zeros((2, 3))
    with pytest.raises(ValueError, match="shape"):
        write_ply(tmp_path / "a.ply", np.zeros((2, 2)), np.zeros(2, dtype=int))
    with pytest.raises(ValueError, match="integers"):
        write_ply(tmp_path / "a.ply", pts, np.zeros(3, dtype=int))
    with pytest.raises(ValueError, match="integers"):
        write_ply(tmp_path / "a.ply", pts, np.zeros(2))
    with pytest.raises(ValueError, match="finite"):
        write_ply(tmp_path / "a.ply", np.array([[0, 0, np.nan], [0, 0, 0]]), np.zeros(2, int))
    with pytest.raises(ValueError, match="ground"):
        write_ply(tmp_path / "a.ply", pts, np.zeros(2, int), np.zeros(3, bool))
    with pytest.raises(ValueError, match="32-bit"):
        write_ply(tmp_path / "a.ply", pts, np.array([0, 2**31]))
    assert not (tmp_path / "a.ply").exists()
