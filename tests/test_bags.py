"""Bags in: PointCloud2 layouts against a per-point oracle, the ring image against brute force,
the three storages, and the shared recordings against their references."""

from __future__ import annotations

import struct

import numpy as np
import pytest

pytest.importorskip("rosbags")

import bagtools  # noqa: E402  (tests/bagtools.py)

from flic_cli.io import open_dataset  # noqa: E402
from flic_cli.io.bag import BagDataset, topics  # noqa: E402
from flic_cli.io.pointcloud2 import cloud_array, estimate_beams, ring_image  # noqa: E402

NEBULA = "sensors/velodyne/nebula_vlp16/1673400471837873222"
NEBULA_PCD = "sensors/velodyne/nebula_vlp16/1673400472138016708.pcd"


# ---- cloud_array: every layout, checked against struct.unpack point by point -------------------


@pytest.mark.parametrize("bigendian", [False, True])
@pytest.mark.parametrize("gap,row_pad,height", [(0, 0, 1), (3, 0, 1), (1, 5, 4), (0, 7, 2)])
def test_cloud_array_matches_struct_oracle(bigendian, gap, row_pad, height):
    rng = np.random.default_rng(gap * 10 + row_pad + height + bigendian)
    n = 40
    cols = {
        "intensity": rng.integers(0, 255, n),
        "x": rng.normal(size=n),
        "ring": rng.integers(0, 16, n),
        "y": rng.normal(size=n),
        "z": rng.normal(size=n),
        "t": rng.random(n),
    }
    types = {"intensity": "u1", "ring": "u2", "t": "f8"}
    st = bagtools.store()
    msg = bagtools.cloud_msg(
        st, cols, types, bigendian=bigendian, gap=gap, row_pad=row_pad, height=height
    )
    arr = cloud_array(msg)
    assert arr.shape == (n,)
    data = bytes(np.asarray(msg.data, np.uint8))
    e = ">" if bigendian else "<"
    codes = {1: "b", 2: "B", 3: "h", 4: "H", 5: "i", 6: "I", 7: "f", 8: "d"}
    width = msg.width
    for i in range(n):
        base = (i // width) * msg.row_step + (i % width) * msg.point_step
        for f in msg.fields:
            (value,) = struct.unpack_from(e + codes[f.datatype], data, base + f.offset)
            assert arr[f.name][i] == value, (i, f.name)


def test_cloud_array_rejects_short_data():
    st = bagtools.store()
    msg = bagtools.cloud_msg(st, {"x": np.zeros(10), "y": np.zeros(10), "z": np.zeros(10)})
    msg.data = msg.data[:-1]
    with pytest.raises(ValueError, match="data holds 119 bytes"):
        cloud_array(msg)


# ---- ring_image: against a brute-force nearest-point image ------------------------------------


@pytest.mark.slow
def test_ring_image_matches_brute_force():
    rng = np.random.default_rng(3)
    n, rings, width = 3000, 8, 64
    ring = rng.integers(0, rings, n)
    az = rng.uniform(-np.pi, np.pi, n)
    el = np.radians(10 - 3 * ring) + rng.normal(0, 1e-3, n)
    r = rng.uniform(1, 30, n)
    xyz = np.stack(
        [r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el)], 1
    ).astype(np.float32)
    xyz[::97] = np.nan  # invalid points are left out
    xyz[5::101] = 0.0
    beams = estimate_beams(xyz, ring, width)
    assert list(beams.row_of_ring) == list(range(rings))  # ring 0 is the top beam here
    image, kept = ring_image(xyz, ring, beams)
    expect = np.zeros((rings, width), np.float32)
    want_kept = np.zeros(n, bool)
    pix = []
    for i in range(n):
        p = xyz[i].astype(np.float64)
        rr = np.sqrt((p**2).sum())
        if not np.isfinite(rr) or rr == 0:
            continue
        az = np.float64(np.arctan2(xyz[i, 1], xyz[i, 0]))  # float32, as the reader computes it
        col = int(np.floor((np.pi - az) * (width / (2 * np.pi)))) % width
        row = beams.row_of_ring[ring[i]]
        if expect[row, col] == 0 or np.float32(rr) < expect[row, col]:
            expect[row, col] = np.float32(rr)
        want_kept[i] = True
        pix.append(row * width + col)
    np.testing.assert_array_equal(kept, want_kept)
    np.testing.assert_array_equal(image.ranges, expect)
    np.testing.assert_array_equal(image.point_pixel, pix)
    assert image.point_counts().sum() == want_kept.sum()
    np.testing.assert_allclose(np.degrees(beams.elevation), 10 - 3 * np.arange(rings), atol=0.01)


def test_estimate_beams_orders_rings_bottom_up_and_fills_empty_rings():
    # VLP-16 style: ring 0 is the lowest beam; ring 3 has no point in this revolution.
    rng = np.random.default_rng(0)
    ring = np.repeat(np.arange(8), 200)
    ring = ring[ring != 3]
    el = np.radians(-7 + 2 * ring)
    az = rng.uniform(-np.pi, np.pi, ring.size)
    xyz = np.stack([10 * np.cos(el) * np.cos(az), 10 * np.cos(el) * np.sin(az), 10 * np.sin(el)], 1)
    b = estimate_beams(xyz, ring, 100)
    assert b.rows == 8
    assert list(b.row_of_ring) == [7, 6, 5, 4, 3, 2, 1, 0]
    np.testing.assert_allclose(np.degrees(b.elevation), [7, 5, 3, 1, -1, -3, -5, -7], atol=1e-6)


# ---- the three storages, with real VLP-16 revolutions as PointCloud2 --------------------------


def _cloud_columns(cloud: np.ndarray) -> dict[str, np.ndarray]:
    return {k: cloud[k] for k in ("x", "y", "z", "intensity", "ring", "time")}


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["ros1", "sqlite3", "mcap", "plain-mcap", "db3-file"])
def test_pointcloud2_bag_in_every_storage(shared_data, tmp_path, kind):
    clouds = bagtools.vlp16_clouds(shared_data, 3)
    st = bagtools.store()
    types = {"intensity": "f4", "ring": "u2", "time": "f4"}
    msgs = [
        (
            "/velodyne_points",
            "sensor_msgs/msg/PointCloud2",
            10**18 + k * 10**8,
            bagtools.cloud_msg(
                st, _cloud_columns(c), types, bigendian=k == 1, gap=2 * k, stamp_ns=10**18 + k
            ),
        )
        for k, c in enumerate(clouds)
    ]
    storage = {"plain-mcap": "mcap", "db3-file": "sqlite3"}.get(kind, kind)
    path = bagtools.write_bag(tmp_path / ("b.bag" if kind == "ros1" else "b"), storage, msgs)
    if kind == "plain-mcap":
        path = next(path.glob("*.mcap"))
    elif kind == "db3-file":
        path = next(path.glob("*.db3"))
    ds = open_dataset(path)
    assert isinstance(ds, BagDataset)
    assert ds.beams.rows == 16 and ds.beams.width == 1800
    for ref, cloud in zip(ds.refs(), clouds, strict=True):
        frame = ds.load(ref)
        xyz = np.stack([cloud["x"], cloud["y"], cloud["z"]], 1)
        image, kept = ring_image(xyz, cloud["ring"], ds.beams)
        np.testing.assert_array_equal(frame.points, xyz[kept])
        np.testing.assert_array_equal(frame.image.ranges, image.ranges)
        np.testing.assert_array_equal(frame.intensity, cloud["intensity"][kept])
        assert frame.stamp_ns == 10**18 + ref.frame and frame.frame_id == "lidar"
    # out of order: seeks by timestamp instead of reading on
    np.testing.assert_array_equal(ds.load(ds.refs()[0]).points[:, 0], clouds[0]["x"])
    info = {t.topic: t for t in topics(path)}
    assert info["/velodyne_points"].count == 3 and info["/velodyne_points"].lidar


def test_organised_cloud_without_ring_takes_its_rows(tmp_path):
    # An Ouster-style organised cloud: 4 rows x 90 columns, row 0 on top, no ring field.
    h, w = 4, 90
    el = np.radians([6.0, 2.0, -2.0, -6.0])[:, None].repeat(w, 1)
    az = np.pi - (np.arange(w) + 0.5) * 2 * np.pi / w
    az = az[None, :].repeat(h, 0)
    r = 5.0 + np.arange(h * w).reshape(h, w) / 100
    r[1, 7] = 0.0  # no return: x = y = z = 0
    cols = {
        "x": (r * np.cos(el) * np.cos(az)).ravel(),
        "y": (r * np.cos(el) * np.sin(az)).ravel(),
        "z": (r * np.sin(el)).ravel(),
    }
    st = bagtools.store()
    msg = bagtools.cloud_msg(st, cols, height=h)
    path = bagtools.write_bag(tmp_path / "o.bag", "ros1", [("/os/points", msg.__msgtype__, 1, msg)])
    ds = open_dataset(path)
    frame = ds.load(ds.refs()[0])
    assert frame.image.shape == (h, w)
    np.testing.assert_allclose(frame.image.ranges, r.astype(np.float32), rtol=1e-6)
    assert frame.points.shape[0] == h * w - 1 and frame.finite.sum() == h * w - 1
    assert "organised" in ds.beams.source


# ---- the shared recordings ---------------------------------------------------------------------


@pytest.mark.slow
def test_vlp16_bag_agrees_with_nebula_reference(shared_data):
    """Message 4 of nebula's bag decoded by flic (velodyne-decoder) against nebula's own decoded
    PCD of that message: measured median 5.2 mm, 98.7 % of points within 2 cm (nearest
    neighbour both ways), point counts 14,816 against 14,831."""
    pypcd4 = pytest.importorskip("pypcd4")
    from scipy.spatial import cKDTree

    ref = pypcd4.PointCloud.from_path(shared_data / NEBULA_PCD).numpy()[:, :3].astype(np.float32)
    ds = open_dataset(shared_data / NEBULA)
    assert ds.msgtype == "velodyne_msgs/msg/VelodyneScan"
    assert [r.frame for r in ds.refs()] == [0, 1, 2, 3]
    frame = ds.load(ds.refs()[3])
    assert frame.points.shape[0] == 14816  # velodyne-decoder's count (data README)
    assert abs(frame.points.shape[0] - ref.shape[0]) / ref.shape[0] < 0.002
    d_ref, _ = cKDTree(frame.points).query(ref)
    d_ours, _ = cKDTree(ref).query(frame.points)
    for d in (d_ref, d_ours):
        assert np.median(d) < 0.007
        assert np.mean(d < 0.02) > 0.97
        assert np.percentile(d, 99) < 0.03
    # rows: 16 beams, 15 of them lit (ring 0 returns nothing in this recording)
    assert frame.image.shape[0] == 16 and ds.sensor().name == "Velodyne VLP16"
    lit = (frame.image.ranges > 0).any(axis=1)
    assert lit.sum() == 15 and not lit[-1]  # the empty ring is the lowest beam (bottom row)
    # every decoded point is in the image; pixels hold the nearest of their points
    assert frame.image.point_pixel.size == frame.points.shape[0]
    # an other message is not this revolution: much worse agreement
    other, _ = cKDTree(ds.load(ds.refs()[0]).points).query(ref)
    assert np.median(other) > np.median(d_ref)


@pytest.mark.slow
def test_ouster_packet_bag_gives_ouster_sdks_frame(shared_data):
    """The shared OS-0-128 bag: metadata from its own topic, one complete frame (frame id
    1798), 128 x 512, 28,751 valid pixels (ouster-sdk 1.0.1's count, data README)."""
    bag = shared_data / "sensors/ouster/512x10_raw.bag"
    info = {t.topic: t for t in topics(bag)}
    assert info["/os_node0/lidar_packets"].lidar and not info["/os_node0/imu_packets"].lidar
    assert info["/os_node0/lidar_packets"].count == 32
    ds = open_dataset(bag)
    assert ds.topic == "/os_node0/lidar_packets"
    assert [r.frame for r in ds.refs()] == [0]
    frame = ds.load(ds.refs()[0])
    assert frame.image.shape == (128, 512)
    assert int(np.count_nonzero(frame.image.ranges)) == frame.points.shape[0] == 28751
    assert ds.sensor().name == "Ouster OS-0-128"
    assert frame.intensity.shape == (28751,) and frame.intensity.max() > 0
    # the points lie at their pixels' ranges (beam origin offset 27.67 mm aside)
    r = np.linalg.norm(frame.points.astype(np.float64), axis=1)
    pix_r = frame.image.ranges.reshape(-1)[frame.image.point_pixel]
    assert np.median(np.abs(r - pix_r)) < 0.03


def test_vlp16_bag_header_and_topics(shared_data):
    info = topics(shared_data / NEBULA)
    assert [(t.topic, t.msgtype, t.count, t.lidar) for t in info] == [
        ("/velodyne_packets", "velodyne_msgs/msg/VelodyneScan", 4, True)
    ]
    ds = open_dataset(shared_data / NEBULA / "1673400471837873222_0.db3")
    frame = ds.load(ds.refs()[0])
    assert frame.frame_id == "velodyne"
    assert frame.stamp_ns == 1673400471737763166


@pytest.mark.slow
def test_flic_info_lists_topics_types_counts(shared_data):
    from typer.testing import CliRunner

    from flic_cli.cli import app

    result = CliRunner().invoke(app, ["info", str(shared_data / "sensors/ouster/512x10_raw.bag")])
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert lines[1].split() == ["/os_node0/imu_packets", "10", "ouster_ros/msg/PacketMsg"]
    assert lines[2].split() == [
        "/os_node0/lidar_packets",
        "32",
        "ouster_ros/msg/PacketMsg",
        "(LiDAR)",
    ]
    assert lines[3].split() == ["/os_node0/metadata", "1", "std_msgs/msg/String"]
    assert "  beams x columns: 128 x 512 (columns from metadata (lidar_mode 512x10))" in lines
    assert "  frames: 1 revolution(s)" in lines
    assert "  sensor: Ouster OS-0-128" in lines


@pytest.mark.slow
def test_velodyne_scan_ros1_and_ros2_give_the_same_frames(shared_data, tmp_path):
    """The shared ROS 2 VelodyneScan messages written to a ROS 1 bag: the same frames."""
    from flic_cli.io.bag import open_reader

    reader = open_reader(shared_data / NEBULA)
    try:
        msgs = [(t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages()]
    finally:
        reader.close()
    bag = bagtools.write_bag(
        tmp_path / "v.bag",
        "ros1",
        [("/velodyne_packets", "velodyne_msgs/msg/VelodyneScan", t, m) for t, m in msgs],
    )
    ros1_ds, ros2_ds = open_dataset(bag), open_dataset(shared_data / NEBULA)
    for ref in ros2_ds.refs():
        a, b = ros1_ds.load(ref), ros2_ds.load(ref)
        np.testing.assert_array_equal(a.points, b.points)
        np.testing.assert_array_equal(a.image.ranges, b.image.ranges)
        assert a.stamp_ns == b.stamp_ns and a.frame_id == b.frame_id == "velodyne"


@pytest.mark.slow
def test_ouster_ros_pointcloud2_gives_the_pcaps_frame(shared_data, tmp_path):
    """The OS-2-128 pcap's revolution written as ouster-ros's organised 48-byte PointCloud2 (ring
    0 = top): the bag gives the pcap's rows, columns and valid points; 95 % of the pcap's valid
    pixels at the same row and column (the rest one column off: columns come from the points'
    azimuth, which the 27.67 mm beam origin offset turns at short range)."""
    pcap = open_dataset(shared_data / "sensors/ouster/OS-2-128-U1_v2.3.0_1024x10.pcap")
    ref_frame = pcap.load(pcap.refs()[0])
    msg = bagtools.ouster_ros_cloud(bagtools.store(), ref_frame)
    bag = bagtools.write_bag(tmp_path / "os", "mcap", [("/ouster/points", msg.__msgtype__, 1, msg)])
    ds = open_dataset(bag)
    frame = ds.load(ds.refs()[0])
    assert "ring field 'ring'" in ds.beams.source
    assert frame.image.shape == ref_frame.image.shape == (128, 1024)
    assert frame.points.shape[0] == ref_frame.points.shape[0] == 119_682
    a, b = frame.image.ranges > 0, ref_frame.image.ranges > 0
    assert a.sum() == b.sum()
    assert np.mean(a[b]) > 0.94
    # rows: ring 0 is the top beam; the elevation of a row, the median over its points, lies
    # within 0.5 deg of the metadata's beam altitude (measured: median +0.31, max 0.47 deg, the
    # points' elevation seen from the sensor origin, 36 mm below the lidar's)
    assert np.all(np.diff(ds.beams.elevation) < 0)
    d = np.degrees(ds.beams.elevation - ref_frame.image.elevation)
    assert np.abs(d).max() < 0.5 and 0.2 < np.median(d) < 0.4
    np.testing.assert_array_equal(frame.points, ref_frame.points)


@pytest.mark.parametrize("kind", ["ros1", "sqlite3", "mcap"])
def test_index_times_equal_the_messages_times(tmp_path, kind):
    """Frames are listed from the bag's own index where it has one (ROS 1, sqlite3): the same
    times as reading every message; MCAP has none here (None: the reader reads the topic)."""
    from flic_cli.io.bag import index_times, open_reader

    st = bagtools.store()
    times = [5, 17, 17, 17, 40, 1000]

    def cloud(k):
        return bagtools.cloud_msg(st, {c: np.arange(1.0, 21.0) + 100 * k for c in "xyz"})

    msgs = [("/p", "sensor_msgs/msg/PointCloud2", t, cloud(k)) for k, t in enumerate(times)]
    msgs.append(("/q", "sensor_msgs/msg/PointCloud2", 9, cloud(99)))
    bag = bagtools.write_bag(tmp_path / ("i.bag" if kind == "ros1" else "i"), kind, msgs)
    reader = open_reader(bag)
    try:
        conns = [c for c in reader.connections if c.topic == "/p"]
        got = index_times(reader, conns, bag)
        read = [t for _, t, _ in reader.messages(connections=conns)]
    finally:
        reader.close()
    assert read == times
    assert got == (None if kind == "mcap" else times)
    with pytest.warns(UserWarning, match="PointCloud2 without ring field and not organised"):
        ds = open_dataset(bag, ["/p"])
    refs = ds.refs()
    assert [r.frame for r in refs] == [0, 1, 2, 3, 4, 5]
    for k in [3, 2, 0, 1, 2, 3, 4, 5, 1]:  # out of order, and messages sharing a time
        assert ds.load(refs[k]).points[0, 0] == 1 + 100 * k, k
