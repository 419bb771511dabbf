"""Bad bags: one line naming the file, the topic and the problem, exit 2, nothing written."""

from __future__ import annotations

import shutil
import sqlite3
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

pytest.importorskip("rosbags")

import bagtools  # noqa: E402

from flic_cli.cli import app  # noqa: E402

runner = CliRunner()
NEBULA = "sensors/velodyne/nebula_vlp16/1673400471837873222"


def _fails(data: Path, out: Path, *extra: str) -> str:
    """Run segment --export mcap; check exit 2, one error line, no output; the line."""
    result = runner.invoke(
        app, ["segment", str(data), "--export", "mcap", "--out", str(out), *extra]
    )
    assert result.exit_code == 2, result.output
    lines = [ln for ln in result.output.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1, result.output
    assert "Traceback" not in result.output
    assert not out.exists() or not any(out.rglob("*")), list(out.rglob("*"))
    return lines[0]


def _string(text: str):
    return bagtools.store().types["std_msgs/msg/String"](data=text)


def _cloud(**cols):
    return bagtools.cloud_msg(bagtools.store(), cols)


XYZ = {"x": np.ones(50), "y": np.arange(50.0), "z": np.zeros(50)}


def test_no_lidar_topic(tmp_path):
    bag = bagtools.write_bag(
        tmp_path / "s.bag", "ros1", [("/chatter", "std_msgs/msg/String", 1, _string("hi"))]
    )
    line = _fails(bag, tmp_path / "out")
    assert (
        str(bag) in line and "no LiDAR topic" in line and "/chatter (std_msgs/msg/String)" in line
    )


def test_unknown_topic_lists_the_lidar_topics(tmp_path):
    cloud = _cloud(**XYZ)
    bag = bagtools.write_bag(
        tmp_path / "c", "mcap", [("/points", "sensor_msgs/msg/PointCloud2", 1, cloud)]
    )
    line = _fails(bag, tmp_path / "out", "--topic", "/nope")
    assert str(bag) in line and "topic /nope: no such topic (LiDAR topics: /points)" in line


def test_several_lidar_topics_need_a_choice(tmp_path):
    cloud = _cloud(**XYZ)
    msgs = [(t, "sensor_msgs/msg/PointCloud2", 1, cloud) for t in ("/front", "/rear")]
    bag = bagtools.write_bag(tmp_path / "two.bag", "ros1", msgs)
    line = _fails(bag, tmp_path / "out")
    assert "2 LiDAR topics, choose one with --topic" in line and "/front" in line
    assert "/rear" in line


def test_a_non_lidar_topic_is_named_as_such(tmp_path):
    msgs = [
        ("/points", "sensor_msgs/msg/PointCloud2", 1, _cloud(**XYZ)),
        ("/chatter", "std_msgs/msg/String", 2, _string("x")),
    ]
    bag = bagtools.write_bag(tmp_path / "m.bag", "ros1", msgs)
    line = _fails(bag, tmp_path / "out", "--topic", "/chatter")
    assert "topic /chatter: std_msgs/msg/String is not a LiDAR message type" in line


@pytest.mark.parametrize("kind", ["ros1", "sqlite3", "mcap"])
def test_pointcloud2_without_xyz(tmp_path, kind):
    cloud = _cloud(a=np.ones(10), b=np.ones(10), intensity=np.ones(10))
    name = "p.bag" if kind == "ros1" else "p"
    bag = bagtools.write_bag(
        tmp_path / name, kind, [("/points", "sensor_msgs/msg/PointCloud2", 1, cloud)]
    )
    line = _fails(bag, tmp_path / "out")
    assert str(bag) in line
    assert "topic /points: PointCloud2 has no x/y/z field (fields: a, b, intensity)" in line


def _frames_bag(tmp_path: Path, kind: str, n: int = 30) -> Path:
    rng = np.random.default_rng(0)
    msgs = []
    for k in range(n):
        cols = {c: rng.normal(size=2000) for c in "xyz"}
        cols["ring"] = np.repeat(np.arange(16), 125)
        msgs.append(
            (
                "/points",
                "sensor_msgs/msg/PointCloud2",
                10**9 * (k + 1),
                bagtools.cloud_msg(bagtools.store(), cols, {"ring": "u2"}),
            )
        )
    return bagtools.write_bag(tmp_path / ("f.bag" if kind == "ros1" else "f"), kind, msgs)


@pytest.mark.parametrize("kind", ["ros1", "mcap", "plain-mcap"])
@pytest.mark.parametrize("keep", [0.5, 0.97])
def test_truncated_bag_or_mcap(tmp_path, kind, keep):
    bag = _frames_bag(tmp_path, "mcap" if kind == "plain-mcap" else kind)
    if kind == "plain-mcap":
        bag = next(bag.glob("*.mcap"))
    target = bag if bag.is_file() else next(bag.glob("*.mcap"))
    data = target.read_bytes()
    cut = tmp_path / "cut"
    if bag.is_dir():
        shutil.copytree(bag, cut)
        (cut / target.name).write_bytes(data[: int(len(data) * keep)])
    else:
        cut = cut.with_suffix(bag.suffix)
        cut.write_bytes(data[: int(len(data) * keep)])
    line = _fails(cut, tmp_path / "out")
    assert str(cut) in line
    assert "cannot be read as a bag" in line or "truncated or corrupt" in line


def test_missing_message_definition(shared_data, tmp_path):
    """A ROS 2 bag (rosbag2 version 5 stores no definitions) of a type flic does not know."""
    bag = tmp_path / "acme"
    shutil.copytree(shared_data / NEBULA, bag)
    for p in bag.iterdir():
        p.chmod(0o644)
    meta = bag / "metadata.yaml"
    meta.write_text(meta.read_text().replace("velodyne_msgs/msg/VelodyneScan", "acme/msg/Scan"))
    con = sqlite3.connect(next(bag.glob("*.db3")))
    con.execute("update topics set type = 'acme/msg/Scan'")
    con.commit()
    con.close()
    line = _fails(bag, tmp_path / "out", "--topic", "/velodyne_packets")
    assert str(bag) in line
    assert "topic /velodyne_packets: the bag stores no message definition of acme/msg/Scan" in line
