"""Bags out: `flic segment BAG --export mcap|bag` read back with a second library (mcap +
mcap-ros2-support, and sqlite3 + mcap-ros2-support's CDR decoder), every point checked."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

pytest.importorskip("rosbags")
pytest.importorskip("mcap_ros2")

from conftest import SHARED_DATA  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from mcap_ros2._dynamic import generate_dynamic  # noqa: E402
from mcap_ros2.decoder import DecoderFactory  # noqa: E402

from flic_cli.cli import app  # noqa: E402
from flic_cli.io import open_dataset, read_predictions  # noqa: E402

NEBULA = "sensors/velodyne/nebula_vlp16/1673400471837873222"
runner = CliRunner()
pytestmark = pytest.mark.shared_data

DTYPES = {7: "<f4", 6: "<u4"}


def _points(msg) -> np.ndarray:
    """A decoded PointCloud2 (mcap-ros2-support's object) as a structured array, by its own
    declared fields."""
    dtype = np.dtype(
        {
            "names": [f.name for f in msg.fields],
            "formats": [DTYPES[f.datatype] for f in msg.fields],
            "offsets": [f.offset for f in msg.fields],
            "itemsize": msg.point_step,
        }
    )
    assert not msg.is_bigendian and msg.height == 1
    return np.frombuffer(bytes(msg.data), dtype=dtype, count=msg.width)


def _read_mcap(folder: Path) -> list[tuple[int, object]]:
    (path,) = folder.glob("*.mcap")
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [(m.log_time, msg) for _, _, m, msg in reader.iter_decoded_messages()]


def _read_db3(folder: Path) -> list[tuple[int, object]]:
    """A rosbag2 sqlite3 file read with sqlite3 and the message definition it stores."""
    (path,) = folder.glob("*.db3")
    con = sqlite3.connect(path)
    try:
        (type_name,) = con.execute("select type from topics where name='/flic/clusters'").fetchone()
        (text,) = con.execute(
            "select encoded_message_definition from message_definitions where topic_type=?",
            (type_name,),
        ).fetchone()
        decode = generate_dynamic(type_name, text)[type_name]
        rows = con.execute("select timestamp, data from messages order by timestamp").fetchall()
    finally:
        con.close()
    return [(t, decode(bytes(data))) for t, data in rows]


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    if not SHARED_DATA.is_dir():
        pytest.skip("../shared/data not present")
    shared_data = SHARED_DATA
    out = tmp_path_factory.mktemp("export")
    result = runner.invoke(
        app,
        ["segment", str(shared_data / NEBULA), "--method", "flic14", "--export", "mcap",
         "--export", "bag", "--out", str(out)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    return out, result.output


@pytest.mark.slow
@pytest.mark.parametrize("storage,read", [("mcap", _read_mcap), ("bag", _read_db3)])
def test_export_round_trips_every_point(shared_data, exported, storage, read):
    out, _ = exported
    messages = read(out / f"1673400471837873222_flic_{storage}")
    ds = open_dataset(shared_data / NEBULA)
    assert len(messages) == len(ds.refs()) == 4
    for ref, (log_time, msg) in zip(ds.refs(), messages, strict=True):
        frame = ds.load(ref)
        cloud = _points(msg)
        assert [f.name for f in msg.fields] == ["x", "y", "z", "intensity", "cluster"]
        np.testing.assert_array_equal(
            np.stack([cloud["x"], cloud["y"], cloud["z"]], 1), frame.points
        )
        np.testing.assert_array_equal(cloud["intensity"], frame.intensity)
        # the clusters are the predictions written beside (one per point as decoded)
        pred = read_predictions(out, ref.sequence, ref.frame, n_points=frame.points.shape[0])
        np.testing.assert_array_equal(cloud["cluster"], pred)
        assert cloud["cluster"].max() > 5
        stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        assert stamp == log_time == frame.stamp_ns
        assert msg.header.frame_id == "velodyne"


@pytest.mark.slow
def test_export_reports_latency(exported):
    _, output = exported
    assert "latency per revolution" in output and "p99" in output and "10 Hz" in output


def test_export_needs_a_bag(small_sample, tmp_path):
    result = runner.invoke(
        app, ["segment", str(small_sample.kitti_root), "--export", "mcap", "--out", str(tmp_path)]
    )
    assert result.exit_code == 2
    assert "--export mcap needs a bag or MCAP input" in result.output
    assert not any(tmp_path.iterdir())


def test_writer_with_label_field_read_back_by_mcap(tmp_path):
    """CloudBagWriter's `label` field (written when semantics are given), by mcap-ros2-support."""
    from flic_cli.io.bag_writer import CloudBagWriter

    rng = np.random.default_rng(5)
    frames = []
    with CloudBagWriter(tmp_path / "lab", "mcap", "/flic/clusters", with_label=True) as w:
        for k in range(3):
            n = 100 + k
            pts = rng.normal(size=(n, 3)).astype(np.float32)
            cluster = rng.integers(0, 9, n)
            label = rng.integers(0, 260, n)
            w.write(10**9 * (k + 1) + 7, f"f{k}", pts, cluster, None, label)
            frames.append((pts, cluster, label))
    got = _read_mcap(tmp_path / "lab")
    assert len(got) == 3
    for k, ((log_time, msg), (pts, cluster, label)) in enumerate(zip(got, frames, strict=True)):
        cloud = _points(msg)
        assert [f.name for f in msg.fields] == ["x", "y", "z", "intensity", "cluster", "label"]
        np.testing.assert_array_equal(np.stack([cloud["x"], cloud["y"], cloud["z"]], 1), pts)
        np.testing.assert_array_equal(cloud["cluster"], cluster)
        np.testing.assert_array_equal(cloud["label"], label)
        assert (cloud["intensity"] == 0).all()
        assert log_time == 10**9 * (k + 1) + 7 and msg.header.frame_id == f"f{k}"
