"""The sensor readers (issue 21): Ouster and Velodyne pcaps, PCD, nuScenes, ``flic info``.

Counts on the shared recordings are those of ../shared/data/sensors/README.md (measured there
with ouster-sdk 1.0.1, velodyne-decoder, rosbags); the packet decoders are also checked on
packets this file writes from known images, and the geometry against a per-pixel evaluation of
Ouster's documented formula.
"""

from __future__ import annotations

import json
import shutil
import struct
from pathlib import Path

import numpy as np
import pytest

from flic_cli.cli import main
from flic_cli.errors import FlicInputError
from flic_cli.io import open_dataset
from flic_cli.io.ouster import (
    PROFILES,
    OusterMeta,
    decode_frames,
    destagger,
    frame_image,
    packet_size,
)

SENSORS = "sensors"
OS2 = "ouster/OS-2-128-U1_v2.3.0_1024x10"
OS1_PCAP = "ouster/OS-1-64_1024x10_fw20.pcap"
VLP16 = "velodyne/vlp16_velodyne_example.pcap"
HELIOS = "pcd/robosense_helios16p_1691031766781547066.pcd"
NEBULA_PCD = "velodyne/nebula_vlp16/1673400472138016708.pcd"
NUSCENES = "nuscenes/n015-2018-07-24-11-22-45+0800__LIDAR_TOP__1532402927647951.pcd.bin"


def _cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in args])
    out, err = capsys.readouterr()
    return int(exc.value.code or 0), out, err


# ---------------------------------------------------------------------------------------------
# Ouster packets written here from known images
# ---------------------------------------------------------------------------------------------


def _meta(profile: str, beams: int = 16, columns: int = 64, shift: int = 3) -> OusterMeta:
    rng = np.random.default_rng(beams)
    alt = np.sort(rng.uniform(-20, 20, beams))[::-1]
    az = rng.uniform(-3, 3, beams)
    js = {
        "beam_altitude_angles": alt.tolist(),
        "beam_azimuth_angles": az.tolist(),
        "lidar_mode": f"{columns}x10",
        "prod_line": "OS-1-16",
        "data_format": {
            "pixels_per_column": beams,
            "columns_per_packet": 16,
            "columns_per_frame": columns,
            "pixel_shift_by_row": [(i % 4) * shift for i in range(beams)],
            "column_window": [0, columns - 1],
            "udp_profile_lidar": profile,
        },
        "lidar_origin_to_beam_origin_mm": 15.806,
    }
    return OusterMeta.from_json(js)


def _packets(
    meta: OusterMeta,
    range_mm: np.ndarray,
    frame_id: int,
    dead: int = -1,
    range2_mm: np.ndarray | None = None,
) -> list:
    """Lidar packets of a staggered (H, W) range image (mm), column ``dead`` marked invalid;
    a dual-return profile's second return is ``range2_mm`` (default: the first + 1 m), its
    flag bits set (ouster-sdk's FLAGS, bits 19-23, which a decoder must mask off), reflectivity
    7 (first) and 5 (second)."""
    head, col_head, chan, foot = PROFILES[meta.profile]
    legacy = meta.profile == "LEGACY"
    out = []
    for start in range(0, meta.columns, 16):
        buf = bytearray(packet_size(meta.profile, meta.beams))
        if not legacy:
            struct.pack_into("<HH", buf, 0, 1, frame_id)
        pos = head
        for m in range(start, start + 16):
            valid = m != dead
            struct.pack_into("<QH", buf, pos, 1000 + m, m)
            if legacy:
                struct.pack_into("<HI", buf, pos + 10, frame_id, 90112 * m // meta.columns)
            else:
                struct.pack_into("<H", buf, pos + 10, 1 if valid else 0)
            p = pos + col_head
            for i in range(meta.beams):
                r = int(range_mm[i, m])
                if chan == 16:
                    r2 = r + 1000 if range2_mm is None else int(range2_mm[i, m])
                    flags = 0b10101 << 19
                    struct.pack_into(
                        "<IIHHH", buf, p, r | flags | 7 << 24, r2 | flags | 5 << 24, 9, 10, 11
                    )
                elif chan == 12:
                    struct.pack_into("<IHHH", buf, p, r | (0xABC << 20 if legacy else 0), 7, 9, 11)
                else:
                    struct.pack_into("<HBB", buf, p, (r // 8) | 0x8000, 7, 9)
                p += chan
            if legacy:
                struct.pack_into("<I", buf, p, 0xFFFFFFFF if valid else 0)
                p += 4
            pos = p
        out.append(bytes(buf))
    return out


@pytest.mark.parametrize("profile", list(PROFILES))
def test_decode_packets_written_from_an_image(profile: str) -> None:
    meta = _meta(profile)
    rng = np.random.default_rng(1)
    limit = (1 << 15) * 8 - 8 if profile == "RNG15_RFL8_NIR8" else (1 << 19) - 1
    img = rng.integers(0, limit, (meta.beams, meta.columns)).astype(np.uint32)
    img[rng.random(img.shape) < 0.2] = 0
    if profile == "RNG15_RFL8_NIR8":
        img -= img % 8  # 8 mm units
    packets = _packets(meta, img, 7, dead=5) + _packets(meta, img // 2, 8)
    frames = list(decode_frames(packets, meta, fields=("reflectivity",)))
    assert [f.frame_id for f in frames] == [7, 8]
    expect = img.copy()
    expect[:, 5] = 0  # the invalid column
    np.testing.assert_array_equal(frames[0].range_mm, expect)
    np.testing.assert_array_equal(
        frames[1].range_mm, img // 2 - (img // 2) % (8 if "15" in profile else 1)
    )
    assert not frames[0].columns[5] and frames[0].columns.sum() == meta.columns - 1
    assert frames[0].complete and frames[0].valid == np.count_nonzero(expect)
    refl = frames[1].fields["reflectivity"]
    assert set(np.unique(refl[img // 2 > 0]).tolist()) <= {7}


DUAL = "RNG19_RFL8_SIG16_NIR16_DUAL"


def _ouster_json(meta: OusterMeta, profile: str | None = None) -> dict:
    return {
        "beam_altitude_angles": meta.altitude_deg.tolist(),
        "beam_azimuth_angles": meta.azimuth_deg.tolist(),
        "lidar_mode": f"{meta.columns}x10",
        "udp_port_lidar": 7502,
        "data_format": {
            "pixels_per_column": meta.beams,
            "columns_per_packet": 16,
            "columns_per_frame": meta.columns,
            "pixel_shift_by_row": meta.pixel_shift.tolist(),
            "column_window": [0, meta.columns - 1],
            "udp_profile_lidar": profile or meta.profile,
        },
    }


def test_ouster_dual_return_pcap(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Dual-return packets written per Ouster's layout (16-byte channels, flag bits set): the
    first return by default, the second with ``--return 2``, each pixel's range exact, the
    reflectivity of the return read; ``--return 3`` is a one-line error."""
    meta = _meta(DUAL)
    rng = np.random.default_rng(8)
    first = rng.integers(1, (1 << 19) - 1, (meta.beams, meta.columns)).astype(np.uint32)
    first[rng.random(first.shape) < 0.1] = 0
    second = rng.integers(1, (1 << 19) - 1, first.shape).astype(np.uint32)
    second[rng.random(first.shape) < 0.5] = 0  # most pixels have no second return
    packets = _packets(meta, first, 3, range2_mm=second)
    d = tmp_path / "in"
    d.mkdir()
    _write_pcap(d / "dual.pcap", packets, 7502)
    (d / "dual.json").write_text(json.dumps(_ouster_json(meta)))
    for which, img in ((None, first), (1, first), (2, second)):
        ds = open_dataset(d / "dual.pcap", reader={"return": which})
        frame = ds.load(ds.refs()[0])
        expect = (destagger(img, meta.pixel_shift) * 0.001).astype(np.float32)
        np.testing.assert_array_equal(frame.image.ranges, expect)
        assert frame.points.shape[0] == np.count_nonzero(img)
        note = f"return {which or 1} of 2 read"
        assert any(note in n for n in ds.sensor(ds.refs()[0]).notes)
    (frame2,) = decode_frames(packets, meta.with_return(2), fields=("reflectivity", "signal"))
    np.testing.assert_array_equal(frame2.range_mm, second)
    assert set(np.unique(frame2.fields["reflectivity"]).tolist()) == {5}
    assert set(np.unique(frame2.fields["signal"]).tolist()) == {10}
    code, _, err = _cli(["info", d / "dual.pcap", "--return", "3"], capsys)
    assert code == 2 and "has 2 returns per pixel: --return 3" in err
    assert len(err.strip().splitlines()) == 1


def test_ouster_profile_flic_cannot_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    meta = _meta("RNG19_RFL8_SIG16_NIR16")
    d = tmp_path / "in"
    d.mkdir()
    _write_pcap(d / "fusa.pcap", _packets(meta, np.ones((16, 64), np.uint32), 1), 7502)
    (d / "fusa.json").write_text(json.dumps(_ouster_json(meta, "FUSA_RNG15_RFL8_NIR8_DUAL")))
    code, _, err = _cli(["info", d / "fusa.pcap"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "'FUSA_RNG15_RFL8_NIR8_DUAL'" in err and DUAL in err


def test_destagger_rolls_each_row_by_its_shift() -> None:
    field = np.arange(4 * 10).reshape(4, 10)
    shift = np.array([0, 1, 3, 12])
    out = destagger(field, shift)
    for i in range(4):
        np.testing.assert_array_equal(out[i], np.roll(field[i], shift[i]))


def _doc_point(meta: OusterMeta, i: int, m: int, r_mm: float) -> np.ndarray:
    """Ouster's documented xyz of beam ``i``, measurement column ``m``, range ``r_mm``, in
    metres in the sensor frame (one pixel at a time, plain math)."""
    import math

    w = meta.columns
    te = 2 * math.pi * (1 - m / w)
    ta = -math.radians(meta.azimuth_deg[i])
    phi = math.radians(meta.altitude_deg[i])
    n = meta.beam_to_lidar[0, 3]
    x = (r_mm - n) * math.cos(te + ta) * math.cos(phi) + n * math.cos(te)
    y = (r_mm - n) * math.sin(te + ta) * math.cos(phi) + n * math.sin(te)
    z = (r_mm - n) * math.sin(phi)
    p = meta.lidar_to_sensor @ np.array([x, y, z, 1.0])
    return p[:3] / 1000.0


def test_frame_points_follow_the_documented_formula() -> None:
    meta = _meta("RNG19_RFL8_SIG16_NIR16")
    rng = np.random.default_rng(3)
    img = rng.integers(500, 80_000, (meta.beams, meta.columns)).astype(np.uint32)
    img[rng.random(img.shape) < 0.3] = 0
    (frame,) = decode_frames(_packets(meta, img, 1), meta)
    image, points = frame_image(frame, meta)
    assert points.shape[0] == np.count_nonzero(img) == np.count_nonzero(image.ranges)
    w = meta.columns
    for j in rng.choice(points.shape[0], 60, replace=False):
        row, col = divmod(int(image.point_pixel[j]), w)
        m = (col - meta.pixel_shift[row]) % w  # destaggered column -> measurement id
        r = float(img[row, m])
        assert image.ranges[row, col] == pytest.approx(r / 1000, rel=1e-6)
        np.testing.assert_allclose(points[j], _doc_point(meta, row, m, r), atol=2e-5)


def test_metadata_defaults_as_ouster_sdk() -> None:
    meta = OusterMeta.from_json(
        {"beam_altitude_angles": [1.0] * 64, "beam_azimuth_angles": [0.0] * 64,
         "lidar_mode": "1024x10"}
    )  # fmt: skip
    assert meta.profile == "LEGACY" and (meta.beams, meta.columns) == (64, 1024)
    assert meta.pixel_shift[:4].tolist() == [18, 12, 6, 0] and meta.pixel_shift.size == 64
    assert meta.beam_to_lidar[0, 3] == 12.163  # ouster-sdk's gen-1 default
    assert meta.lidar_to_sensor[2, 3] == 36.18 and meta.lidar_to_sensor[0, 0] == -1
    assert set(meta.defaulted) == {
        "data_format", "lidar_origin_to_beam_origin_mm", "lidar_to_sensor_transform"
    }  # fmt: skip


# ---------------------------------------------------------------------------------------------
# The shared recordings
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("path", "beams", "columns", "valid"),
    [(OS2 + ".pcap", 128, 1024, 119_682), (OS1_PCAP, 64, 1024, 16_749)],
)
def test_ouster_pcaps(shared_data: Path, path: str, beams: int, columns: int, valid: int) -> None:
    ds = open_dataset(shared_data / SENSORS / path)
    assert ds.format == "ouster"
    (ref,) = ds.refs()
    frame = ds.load(ref)
    assert frame.image.shape == (beams, columns)
    assert np.count_nonzero(frame.image.ranges) == valid == frame.points.shape[0]
    assert ds.sensor(ref).angles_from == "metadata"
    # every point lies at its pixel's range from the beam origin (within the origin offset)
    r = np.linalg.norm(frame.points, axis=1)
    own = frame.image.ranges.reshape(-1)[frame.image.point_pixel]
    assert np.abs(r - own).max() < 0.06


def test_ouster_rng15_packets_of_the_ros_bag(shared_data: Path) -> None:
    """The low-data-rate profile's only sample: packets of a ROS 1 bag, read with rosbags."""
    pytest.importorskip("rosbags")
    from rosbags.rosbag1 import Reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(get_types_from_msg("uint8[] buf", "ouster_ros/msg/PacketMsg"))
    with Reader(shared_data / SENSORS / "ouster/512x10_raw.bag") as bag:
        by_topic = {c.topic: c for c in bag.connections}
        meta_msg = [
            store.deserialize_ros1(raw, c.msgtype)
            for c, _, raw in bag.messages(connections=[by_topic["/os_node0/metadata"]])
        ][0]
        packets = [
            bytes(store.deserialize_ros1(raw, c.msgtype).buf)
            for c, _, raw in bag.messages(connections=[by_topic["/os_node0/lidar_packets"]])
        ]
    meta = OusterMeta.from_json(json.loads(meta_msg.data))
    assert meta.profile == "RNG15_RFL8_NIR8" and (meta.beams, meta.columns) == (128, 512)
    (frame,) = decode_frames(packets, meta)
    assert frame.frame_id == 1798 and frame.complete
    image, points = frame_image(frame, meta)
    assert np.count_nonzero(image.ranges) == 28_751 == points.shape[0]


def test_velodyne_pcap(shared_data: Path) -> None:
    ds = open_dataset(shared_data / SENSORS / VLP16)
    assert ds.format == "velodyne"
    (ref,) = ds.refs()  # one complete rotation; the remainder is left out
    assert ds.infos[ref.sequence].partial == ["remainder of 2,603 points"]
    frame = ds.load(ref)
    assert frame.image.shape[0] == 16
    assert frame.points.shape[0] == 29_027 == np.count_nonzero(frame.image.ranges)
    # rows are ordered top to bottom: each row's points lie near its elevation
    el = np.arctan2(frame.points[:, 2], np.linalg.norm(frame.points[:, :2], axis=1))
    row = frame.image.point_pixel // frame.image.shape[1]
    assert np.abs(el - frame.image.elevation[row]).max() < np.radians(0.6)
    assert ds.sensor(ref).angles_from == "decoder"


def test_velodyne_load_equals_one_decoding_pass(shared_data: Path) -> None:
    import velodyne_decoder as vd

    path = shared_data / SENSORS / VLP16
    (first, *_) = vd.read_pcap(str(path), vd.Config(model=vd.Model.VLP16))
    ds = open_dataset(path)
    frame = ds.load(ds.refs()[0])
    np.testing.assert_array_equal(frame.points, first.points[:, :3])


def _same_frame(a, b) -> None:  # noqa: ANN001
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.image.ranges, b.image.ranges)
    np.testing.assert_array_equal(a.image.point_pixel, b.image.point_pixel)
    np.testing.assert_array_equal(a.image.point_counts(), b.image.point_counts())


def test_velodyne_kept_packets_equal_the_file_read(
    shared_data: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A frame from the packets kept at open, from the file (a capture over the memory limit)
    and in a process the dataset was pickled to (the packet objects left behind): the same
    points and image, over both complete turns of a written HDL-32E capture and the VLP-16's."""
    import pickle

    from flic_cli.io import velodyne

    for path in (shared_data / SENSORS / VLP16, _velodyne_capture(tmp_path, "HDL32E")[0]):
        kept = open_dataset(path)
        assert kept.infos[kept.refs()[0].sequence].state.packets is not None
        with monkeypatch.context() as m:
            m.setattr(velodyne, "KEEP_PACKETS_MAX_BYTES", 0)
            read = open_dataset(path)
        assert read.infos[read.refs()[0].sequence].state.packets is None
        moved = pickle.loads(pickle.dumps(kept))
        assert moved.infos[moved.refs()[0].sequence].state.packets is None
        for ref in kept.refs():
            frame = kept.load(ref)
            _same_frame(frame, read.load(ref))
            _same_frame(frame, moved.load(ref))


@pytest.mark.parametrize(
    ("path", "points", "rows"), [(HELIOS, 15_258, 16), (NEBULA_PCD, 14_831, 16)]
)
def test_pcd_recordings(shared_data: Path, path: str, points: int, rows: int) -> None:
    ds = open_dataset(shared_data / SENSORS / path)
    assert ds.format == "pcd"
    frame = ds.load(ds.refs()[0])
    assert frame.n_read == points == frame.points.shape[0]
    assert frame.image.shape[0] == rows
    el = np.arctan2(frame.points[:, 2], np.linalg.norm(frame.points[:, :2], axis=1))
    row = frame.image.point_pixel // frame.image.shape[1]
    assert np.median(np.abs(el - frame.image.elevation[row])) < np.radians(0.5)
    # columns follow the azimuth: a pixel's nominal azimuth is within a few columns of its points
    w = frame.image.shape[1]
    col = frame.image.point_pixel % w
    az = np.arctan2(frame.points[:, 1], frame.points[:, 0])
    d = np.angle(np.exp(1j * (az - frame.image.azimuth[col])))
    assert np.median(np.abs(d)) < 2 * (2 * np.pi / w) + np.radians(1.0)


def test_nuscenes_sweep(shared_data: Path) -> None:
    ds = open_dataset(shared_data / SENSORS / NUSCENES)
    assert ds.format == "nuscenes"
    frame = ds.load(ds.refs()[0])
    assert frame.n_read == 34_688 and frame.image.shape == (32, 1084)
    assert frame.points.shape[0] == 34_688 - 8_029  # within 1 m: left out
    assert np.count_nonzero(frame.image.ranges) == frame.points.shape[0]  # one point per pixel


@pytest.mark.slow
@pytest.mark.parametrize("path", [OS2 + ".pcap", OS1_PCAP, VLP16, HELIOS, NEBULA_PCD, NUSCENES])
def test_info_on_every_recording(
    shared_data: Path, path: str, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, err = _cli(["info", shared_data / SENSORS / path], capsys)
    assert code == 0, err
    expect = {
        OS2 + ".pcap": ("128 x 1024", "119,682", "metadata"),
        OS1_PCAP: ("64 x 1024", "16,749", "metadata"),
        VLP16: ("16 x 1848", "29,027", "decoder"),
        HELIOS: ("16 x ", "15,258", "fields"),
        NEBULA_PCD: ("16 x 1800", "14,831", "fields"),
        NUSCENES: ("32 x 1084", "26,659 (of 34,688", "fields"),
    }[path]
    assert f"beams x columns: {expect[0]}" in out
    assert f"points per frame: {expect[1]}" in out
    assert f"beam angles from: {expect[2]}" in out and "projection coverage" in out


@pytest.mark.slow
def test_segment_writes_one_label_per_point(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "seg"
    code, _, err = _cli(["segment", shared_data / SENSORS / OS1_PCAP, "--out", out], capsys)
    assert code == 0, err
    (label,) = out.rglob("*.label")
    assert label.stat().st_size == 4 * 16_749


# ---------------------------------------------------------------------------------------------
# PCD encodings and azimuth units
# ---------------------------------------------------------------------------------------------


def _ring_cloud(beams: int = 16, width: int = 900) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    el = np.radians(np.linspace(-15, 15, beams))
    az = np.pi - (np.arange(width) + 0.5) * 2 * np.pi / width
    rng = np.random.default_rng(0)
    e, a = np.meshgrid(el, az, indexing="ij")
    r = rng.uniform(2, 30, e.shape)
    xyz = np.stack([r * np.cos(e) * np.cos(a), r * np.cos(e) * np.sin(a), r * np.sin(e)], -1)
    ring = np.broadcast_to(np.arange(beams)[:, None], e.shape)
    return xyz.reshape(-1, 3).astype(np.float32), ring.reshape(-1), a.reshape(-1)


@pytest.mark.parametrize("encoding", ["ascii", "binary", "binary_compressed"])
@pytest.mark.parametrize("unit", ["radians", "degrees", "centidegrees"])
def test_pcd_encodings_and_units(tmp_path: Path, encoding: str, unit: str) -> None:
    from pypcd4 import Encoding, PointCloud

    xyz, ring, az = _ring_cloud()
    # the field as nebula writes it: clockwise from x, in [0, 2 pi) or 0.01 degree
    field = np.mod(-az, 2 * np.pi)
    if unit != "radians":
        field = np.degrees(field) * (100 if unit == "centidegrees" else 1)
    pc = PointCloud.from_points(
        [xyz[:, 0], xyz[:, 1], xyz[:, 2], ring.astype(np.uint16), field.astype(np.float32)],
        ("x", "y", "z", "ring", "azimuth"),
        (np.float32, np.float32, np.float32, np.uint16, np.float32),
    )
    path = tmp_path / f"cloud_{encoding}.pcd"
    pc.save(path, encoding=Encoding(encoding))
    ds = open_dataset(path)
    frame = ds.load(ds.refs()[0])
    assert frame.image.shape == (16, 900)
    # every point in its own pixel: row = 15 - ring, column = its azimuth's column
    expect = (15 - ring) * 900 + np.floor((np.pi - az) / (2 * np.pi) * 900).astype(int) % 900
    assert np.mean(frame.image.point_pixel == expect) > 0.99
    assert np.count_nonzero(frame.image.ranges) > 0.99 * xyz.shape[0]


def test_pcd_without_ring_estimates_the_beams(tmp_path: Path) -> None:
    from pypcd4 import PointCloud

    xyz, ring, _ = _ring_cloud()
    path = tmp_path / "xyz.pcd"
    PointCloud.from_xyz_points(xyz).save(path)
    ds = open_dataset(path)
    frame = ds.load(ds.refs()[0])
    assert frame.image.shape[0] == 16
    assert ds.sensor(ds.refs()[0]).angles_from == "estimated"
    np.testing.assert_array_equal(frame.image.point_pixel // frame.image.shape[1], 15 - ring)


def _xyz_only_pcd(path: Path, beams: int = 32, width: int = 256) -> tuple[np.ndarray, int]:
    """An xyz-only PCD of a sensor whose beams are 0.3 deg apart (closer than the 0.4 deg gap
    the beam estimate looks for), ``width`` firings of every beam, every 7th point NaN (no
    return). Returns the true pixel of every stored point (-1 for the NaN ones) and N."""
    from pypcd4 import PointCloud

    el = np.radians(np.arange(beams) * 0.3 - 5)
    az = np.pi - (np.arange(width) + 0.5) * 2 * np.pi / width
    e, a = np.meshgrid(el, az, indexing="ij")
    r = 8 + 4 * np.sin(3 * a) + 0.05 * np.arange(beams)[:, None]  # smooth walls: clusters form
    xyz = np.stack([r * np.cos(e) * np.cos(a), r * np.cos(e) * np.sin(a), r * np.sin(e)], -1)
    xyz = xyz.reshape(-1, 3).astype(np.float32)
    pixel = ((beams - 1 - np.arange(beams))[:, None] * width + np.arange(width)).reshape(-1)
    order = np.random.default_rng(3).permutation(xyz.shape[0])  # unorganised, any order
    xyz, pixel = xyz[order], pixel[order]
    xyz[::7] = np.nan
    pixel[::7] = -1
    PointCloud.from_xyz_points(xyz).save(path)
    return pixel, xyz.shape[0]


def test_pcd_rows_and_columns_options(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """An xyz-only PCD whose beams the elevation gaps cannot separate: without ``--rows`` a
    one-line error; with ``--rows 32 --columns 512`` every point in its true pixel, and every
    method of the default config gives one label per stored point (NaN ones included)."""
    import flic_cli.api as flic

    path = tmp_path / "xyz.pcd"
    pixel, n = _xyz_only_pcd(path)
    code, _, err = _cli(["info", path], capsys)
    assert code == 2 and "no beam structure" in err and len(err.strip().splitlines()) == 1
    reader = {"rows": 32, "columns": 256}
    ds = open_dataset(path, reader=reader)
    model = ds.sensor(ds.refs()[0])
    assert (model.beams, model.columns, model.columns_from) == (32, 256, "--columns")
    frame = ds.load(ds.refs()[0])
    assert frame.image.shape == (32, 256) and frame.n_read == n
    np.testing.assert_array_equal(frame.image.point_pixel, pixel[pixel >= 0])
    np.testing.assert_allclose(np.degrees(np.diff(model.elevation)), -0.3, atol=1e-3)
    # the columns estimate alone (rows given) finds the same 256
    assert open_dataset(path, reader={"rows": 32}).sensor(ds.refs()[0]).columns == 256
    frame = flic.load_frame(path, reader=reader)
    clusters = {}
    for method in flic.methods():
        if method in ("alpine", "alpine-k32"):  # per semantic class: a PCD has none
            with pytest.raises(FlicInputError, match="--semantics"):
                flic.segment_frame(frame, method)
            continue
        labels = flic.segment_frame(frame, method)
        assert labels.shape == (n,), method
        assert (labels[pixel < 0] == 0).all(), method  # no return, no cluster
        clusters[method] = int(np.unique(labels[labels > 0]).size)
    assert clusters["bogoslavskyi"] >= 1 and clusters["flic14"] >= 1, clusters
    out = tmp_path / "out"
    args = ["segment", path, "--rows", "32", "--columns", "256", "--out", out]
    code, _, err = _cli(args, capsys)
    assert code == 0, err
    (pred,) = (out / "sequences" / "xyz" / "predictions").glob("*.label")
    assert np.fromfile(pred, dtype=np.uint32).size == n
    code, out_text, _ = _cli(["info", path, "--rows", "32", "--columns", "256"], capsys)
    assert code == 0 and "32 x 256 (columns from --columns)" in out_text


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--columns", "4"], "integer >= 8"),
        (["--rows", "0"], "integer >= 1"),
        (["--rows", "20000"], "fewer distinct elevations than the 20000 rows"),
    ],
)
def test_pcd_bad_reader_options(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], words: str
) -> None:
    path = tmp_path / "xyz.pcd"
    _xyz_only_pcd(path, beams=4, width=64)
    code, _, err = _cli(["info", path, *args], capsys)
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1, err


def test_reader_options_on_a_format_without_them(
    shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = _cli(["info", shared_data / SENSORS / VLP16, "--columns", "1800"], capsys)
    assert code == 2 and "does not apply to velodyne data" in err
    code, _, err = _cli(["info", shared_data / SENSORS / HELIOS, "--rows", "16"], capsys)
    assert code == 2 and "has a ring field ('channel')" in err


def test_ascii_pcd_reads_as_pypcd4_does(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The ASCII data section through pandas: the same values as pypcd4's own reader (NaN,
    integer fields, a field of COUNT 2), and a cut-off file is an error, not fewer points."""
    from pypcd4 import Encoding, MetaData, PointCloud

    from flic_cli.io.pcd import read_pcd

    rng = np.random.default_rng(4)
    n = 500
    dtype = [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("ring", "<u2"),
             ("t__0000", "<f8"), ("t__0001", "<f8"), ("i", "i1")]  # fmt: skip
    data = np.empty(n, dtype)
    for name, dt in dtype:
        data[name] = rng.normal(0, 50, n).astype(dt) if "f" in dt else rng.integers(0, 60, n)
    data["x"][::9] = np.nan
    meta = MetaData.model_validate(
        {"fields": ("x", "y", "z", "ring", "t", "i"), "size": (4, 4, 4, 2, 8, 1),
         "type": ("F", "F", "F", "U", "F", "I"), "count": (1, 1, 1, 1, 2, 1), "points": n,
         "width": n, "height": 1}
    )  # fmt: skip
    path = tmp_path / "a.pcd"
    PointCloud(meta, data).save(path, encoding=Encoding.ASCII)
    ours, theirs = read_pcd(path), PointCloud.from_path(path).pc_data
    assert ours.dtype == theirs.dtype
    for name in theirs.dtype.names:
        np.testing.assert_array_equal(ours[name], theirs[name])
    xyz = read_pcd(path, ("x", "y", "z"))
    assert xyz.dtype.names == ("x", "y", "z")
    np.testing.assert_array_equal(xyz["y"], theirs["y"])
    text = path.read_bytes()
    head, data = text.split(b"DATA ascii\n")
    spaced = data.replace(b" ", b"  ").replace(b"\n", b" \n")  # other writers' spacing
    (tmp_path / "spaced.pcd").write_bytes(head + b"DATA ascii\n" + spaced)
    loose = read_pcd(tmp_path / "spaced.pcd")
    for name in theirs.dtype.names:
        np.testing.assert_array_equal(loose[name], theirs[name])
    (tmp_path / "cut.pcd").write_bytes(text[: len(text) * 2 // 3].rsplit(b"\n", 1)[0] + b"\n")
    code, _, err = _cli(["info", tmp_path / "cut.pcd"], capsys)
    assert code == 2 and "of the 500 points its header declares" in err, err


def test_ascii_pcd_hard_numbers_parse_as_pypcd4_does(tmp_path: Path) -> None:
    """Numbers where a fast float parser can be off by one unit in the last place: the shortest
    repr of random doubles (17 digits), exponents from 1e-320 (subnormal) to 1e300 in a double
    field, float32 fields given the exact decimal midpoint between two floats (25 and 40
    digits, where string -> double -> float rounds twice), nan / inf: pandas' reader (flic's)
    gives the same bytes as pypcd4's ``numpy.loadtxt``."""
    from pypcd4 import PointCloud

    from flic_cli.io.pcd import read_pcd

    rng = np.random.default_rng(21)
    n = 3000
    f = rng.normal(0, 50, (n, 3)).astype(np.float32)
    mid = (f.astype(np.float64) + np.nextafter(f, np.float32(np.inf)).astype(np.float64)) / 2
    wide = rng.normal(0, 1, n) * 10.0 ** rng.uniform(-320, 300, n)
    lines = []
    for i in range(n):
        x, y, z = (f"{v:.25g}" if i % 2 else f"{v:.40f}" for v in mid[i])
        t = repr(float(wide[i])) if i % 3 else repr(float(rng.normal(0, 50)))
        lines.append(f"{x} {y} {z} {t}")
    lines[5] = "nan nan nan nan"
    lines[7] = "1.5 -inf inf -0.0"
    head = (
        "VERSION 0.7\nFIELDS x y z t\nSIZE 4 4 4 8\nTYPE F F F F\nCOUNT 1 1 1 1\n"
        f"WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA ascii\n"
    )
    path = tmp_path / "hard.pcd"
    path.write_text(head + "\n".join(lines) + "\n")
    ours, theirs = read_pcd(path), PointCloud.from_path(path).pc_data
    assert ours.dtype == theirs.dtype
    assert ours.tobytes() == theirs.tobytes()
    xyz = read_pcd(path, ("x", "y", "z"))  # the frame load's path: x, y, z only
    assert xyz.dtype.names == ("x", "y", "z")
    assert all(xyz[c].tobytes() == theirs[c].tobytes() for c in "xyz")


# ---------------------------------------------------------------------------------------------
# nuScenes labels: evaluate scores them
# ---------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_nuscenes_evaluate_scores_a_label_file(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Objects defined as FLIC's own clusters (category car) must score IoU_mu = 100 % for FLIC
    in the no-ground setting; the ground (driveable surface, by height) is removed by label."""
    import pandas as pd

    from flic_cli.io.nuscenes import read_pcd_bin

    data = tmp_path / "nus"
    data.mkdir()
    src = shared_data / SENSORS / NUSCENES
    shutil.copy(src, data / src.name)
    pts = read_pcd_bin(src)
    cat = np.where(pts[:, 2] < -1.6, 24, 28).astype(np.int64)  # ground, else man-made
    npz = data / (src.name[: -len(".pcd.bin")] + "_panoptic.npz")
    np.savez(npz, data=(cat * 1000).astype(np.uint16))
    seg = tmp_path / "seg"
    code, _, err = _cli(
        ["segment", data, "--out", seg, "--method", "flic", "--setting", "no-ground"], capsys
    )
    assert code == 0, err
    (label,) = seg.rglob("*.label")
    from flic_cli.labels import instance

    pred = instance(np.fromfile(label, dtype="<u4"))
    ids, counts = np.unique(pred[pred > 0], return_counts=True)
    big = ids[counts >= 100][:5]
    assert big.size >= 2
    inst = np.zeros(pts.shape[0], dtype=np.int64)
    for k, cid in enumerate(big, start=1):
        inst[pred == cid] = k
    cat[inst > 0] = 17  # vehicle.car
    np.savez(npz, data=(cat * 1000 + inst).astype(np.uint16))
    out = tmp_path / "eval"
    code, _, err = _cli(
        ["evaluate", data, "--methods", "flic0", "--setting", "no-ground", "--out", out], capsys
    )
    assert code == 0, err
    table = pd.read_csv(out / "per_object.csv")
    assert len(table) == big.size
    assert np.allclose(table["iou"], 1.0)
    # sweep-threshold on the same labels: FLIC's own threshold gives IoU_mu 100 %
    sweep = tmp_path / "sweep"
    args = ["sweep-threshold", data, "--method", "flic", "--setting", "no-ground"]
    code, _, err = _cli([*args, "--from", "0.5", "--to", "1.0", "--out", sweep], capsys)
    assert code == 0, err
    curve = pd.read_csv(sweep / "sweep.csv")
    own = curve[np.isclose(curve["value"], 0.75)]
    assert len(own) == 1 and float(own["iou_mu"].iloc[0]) == 100.0


# ---------------------------------------------------------------------------------------------
# Bad input: one line naming the file, exit 2, nothing written
# ---------------------------------------------------------------------------------------------


def _bad(args: list, capsys: pytest.CaptureFixture[str], out: Path, *words: str) -> str:
    code, _, err = _cli([*args, "--out", out], capsys)
    # (the bad files lie in tmp_path / "in", the output would go to tmp_path / "o")
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for w in words:
        assert w in lines[0], lines[0]
    assert not out.exists()
    return lines[0]


def test_truncated_pcap(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = shared_data / SENSORS / VLP16
    bad = tmp_path / "cut.pcap"
    bad.write_bytes(src.read_bytes()[:-500])
    _bad(["segment", bad], capsys, tmp_path / "o", str(bad), "truncated")


def test_pcap_without_lidar_packets(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import dpkt

    bad = tmp_path / "dns.pcap"
    with open(bad, "wb") as f:
        w = dpkt.pcap.Writer(f)
        for k in range(5):
            udp = dpkt.udp.UDP(sport=5353, dport=53, data=b"x" * 40)
            udp.ulen = len(udp)
            ip = dpkt.ip.IP(src=b"\x0a\0\0\1", dst=b"\x0a\0\0\2", p=17, data=udp)
            ip.len = len(ip)
            w.writepkt(bytes(dpkt.ethernet.Ethernet(data=ip)), ts=float(k))
    _bad(["segment", bad], capsys, tmp_path / "o", str(bad), "no lidar packets")


def _os2_with_meta(shared_data: Path, tmp_path: Path, change) -> Path:  # noqa: ANN001
    pcap = tmp_path / "os2.pcap"
    shutil.copy(shared_data / SENSORS / (OS2 + ".pcap"), pcap)
    meta = json.loads((shared_data / SENSORS / (OS2 + ".json")).read_text())
    change(meta)
    (tmp_path / "os2.json").write_text(json.dumps(meta))
    return pcap


def test_metadata_beams_do_not_match(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    def to_64(m: dict) -> None:
        for k in ("beam_altitude_angles", "beam_azimuth_angles"):
            m[k] = m[k][::2]
        m["data_format"]["pixel_shift_by_row"] = m["data_format"]["pixel_shift_by_row"][::2]
        m["data_format"]["pixels_per_column"] = 64

    pcap = _os2_with_meta(shared_data, tmp_path, to_64)
    line = _bad(["segment", pcap], capsys, tmp_path / "o", str(pcap), "does not match")
    assert "128 beams" in line  # names what the packets fit


def test_metadata_profile_does_not_match(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    def legacy(m: dict) -> None:
        m["data_format"]["udp_profile_lidar"] = "LEGACY"

    pcap = _os2_with_meta(shared_data, tmp_path, legacy)
    line = _bad(["segment", pcap], capsys, tmp_path / "o", str(pcap), "does not match")
    assert "RNG19_RFL8_SIG16_NIR16" in line


def test_metadata_columns_do_not_match(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    def to_512(m: dict) -> None:
        m["lidar_mode"] = "512x20"
        m["data_format"]["columns_per_frame"] = 512
        m["data_format"]["column_window"] = [0, 511]

    pcap = _os2_with_meta(shared_data, tmp_path, to_512)
    _bad(["segment", pcap], capsys, tmp_path / "o", str(pcap), "measurement id", "512 columns")

    def to_2048(m: dict) -> None:
        m["lidar_mode"] = "2048x10"
        m["data_format"]["columns_per_frame"] = 2048
        m["data_format"]["column_window"] = [0, 2047]

    pcap = _os2_with_meta(shared_data, tmp_path, to_2048)
    _bad(["segment", pcap], capsys, tmp_path / "o2", str(pcap), "2048", "does not match")


def test_pcd_without_xyz(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "noxyz.pcd"
    bad.write_text(
        "VERSION 0.7\nFIELDS intensity ring\nSIZE 4 2\nTYPE F U\nCOUNT 1 1\nWIDTH 2\n"
        "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1.0 0\n2.0 1\n"
    )
    _bad(["segment", bad], capsys, tmp_path / "o", str(bad), "x/y/z")


def test_pcd_bin_size_not_a_multiple_of_20(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "cut__LIDAR_TOP__1.pcd.bin"
    bad.write_bytes((shared_data / SENSORS / NUSCENES).read_bytes()[:-7])
    _bad(["segment", bad], capsys, tmp_path / "o", str(bad), "multiple of 20")


# ---------------------------------------------------------------------------------------------
# ouster-sdk: the same ranges, pixel by pixel (where it is installed)
# ---------------------------------------------------------------------------------------------


def _sdk_python() -> str:
    """An interpreter with ouster-sdk: this one, or ``FLIC_OUSTER_SDK_PYTHON`` (a separate venv,
    since ouster-sdk's pins clash with flic's environment); skip without one."""
    import importlib.util
    import os
    import sys

    try:
        if importlib.util.find_spec("ouster.sdk") is not None:
            return sys.executable
    except ModuleNotFoundError:
        pass
    env = os.environ.get("FLIC_OUSTER_SDK_PYTHON")
    if env and Path(env).exists():
        return env
    pytest.skip("ouster-sdk is not installed (set FLIC_OUSTER_SDK_PYTHON to a venv's python)")


@pytest.mark.slow
@pytest.mark.parametrize(
    ("pcap", "meta"),
    [(OS2 + ".pcap", OS2 + ".json"), (OS1_PCAP, "ouster/OS-1-64_sensor_config_reduced.json")],
)
def test_ranges_equal_ouster_sdk(shared_data: Path, tmp_path: Path, pcap: str, meta: str) -> None:
    import subprocess

    from flic_cli.io.pcap import read_payloads

    python = _sdk_python()
    script = Path(__file__).resolve().parents[1] / "scripts/sensors/ouster_sdk_dump.py"
    npz = tmp_path / "sdk.npz"
    src = shared_data / SENSORS
    subprocess.run([python, script, src / pcap, src / meta, npz], check=True, capture_output=True)
    sdk = np.load(npz)
    ds = open_dataset(src / pcap)
    (ref,) = ds.refs()
    state = ds.infos[ref.sequence].state
    (raw,) = decode_frames(read_payloads(state.index, state.packets[0]), state.meta)
    np.testing.assert_array_equal(destagger(raw.range_mm, state.meta.pixel_shift), sdk["range_0"])
    frame = ds.load(ref)
    np.testing.assert_array_equal(frame.image.ranges, (sdk["range_0"] * 0.001).astype(np.float32))
    xyz = sdk["xyz_0"].reshape(-1, 3)[frame.image.point_pixel]
    np.testing.assert_allclose(frame.points, xyz, atol=1e-4)


# ---------------------------------------------------------------------------------------------
# Containers: pcapng, folders of recordings, metadata next to the pcap
# ---------------------------------------------------------------------------------------------


def test_pcapng_gives_the_same_frame(shared_data: Path, tmp_path: Path) -> None:
    import dpkt

    src = shared_data / SENSORS / VLP16
    ng = tmp_path / "in" / "vlp16.pcapng"
    ng.parent.mkdir()
    with open(src, "rb") as f, open(ng, "wb") as g:
        w = dpkt.pcapng.Writer(g)
        for ts, buf in dpkt.pcap.Reader(f):
            w.writepkt(buf, ts=ts)
    a = open_dataset(src)
    b = open_dataset(ng)
    assert b.format == "velodyne" and b.infos["vlp16"].state.index.offset is None
    np.testing.assert_array_equal(a.load(a.refs()[0]).points, b.load(b.refs()[0]).points)


def test_a_folder_of_ouster_pcaps_pairs_each_with_its_json(shared_data: Path) -> None:
    ds = open_dataset(shared_data / SENSORS / "ouster")
    assert ds.format == "ouster"
    names = {r.sequence: ds.infos[r.sequence].sensor for r in ds.refs()}
    assert set(names) == {"OS-2-128-U1_v2.3.0_1024x10", "OS-1-64_1024x10_fw20"}
    assert names["OS-1-64_1024x10_fw20"].beams == 64  # OS-1-64_sensor_config_reduced.json
    assert names["OS-2-128-U1_v2.3.0_1024x10"].beams == 128


def test_metadata_ambiguous_names_are_an_error(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    d = tmp_path / "in"
    d.mkdir()
    shutil.copy(shared_data / SENSORS / OS1_PCAP, d / "rec_a.pcap")
    for name in ("rec_1.json", "rec_2.json"):
        shutil.copy(shared_data / SENSORS / "ouster/OS-1-64_sensor_config_reduced.json", d / name)
    line = _bad(["segment", d / "rec_a.pcap"], capsys, tmp_path / "o", "rec_a.pcap")
    assert "equally well" in line
    shutil.copy(d / "rec_1.json", d / "rec_a.json")  # the same name wins
    assert open_dataset(d / "rec_a.pcap").format == "ouster"


def test_nuscenes_root_finds_labels_through_sample_data(shared_data: Path, tmp_path: Path) -> None:
    from flic_cli.classes import thing_mask

    root = tmp_path / "nuscenes"
    lidar = root / "samples" / "LIDAR_TOP"
    lidar.mkdir(parents=True)
    src = shared_data / SENSORS / NUSCENES
    shutil.copy(src, lidar / src.name)
    (root / "v1.0-mini").mkdir()
    rows = [{"token": "abc123", "filename": f"samples/LIDAR_TOP/{src.name}"}]
    (root / "v1.0-mini" / "sample_data.json").write_text(json.dumps(rows))
    (root / "panoptic" / "v1.0-mini").mkdir(parents=True)
    n = src.stat().st_size // 20
    data = np.full(n, 24 * 1000, dtype=np.uint16)  # driveable surface
    data[:100] = 17 * 1000 + 3  # car 3
    data[100:150] = 9 * 1000 + 1  # a barrier: no SemanticKITTI thing (fence)
    np.savez(root / "panoptic" / "v1.0-mini" / "abc123_panoptic.npz", data=data)
    ds = open_dataset(root, require_labels=True)
    assert ds.format == "nuscenes"
    frame = ds.load(ds.refs()[0])
    assert frame.labels is not None and frame.labels.shape[0] == frame.points.shape[0]
    from flic_cli.io.nuscenes import read_panoptic
    from flic_cli.labels import instance, semantic

    full = read_panoptic(frame.ref.label_path, n)
    sem, inst = semantic(full), instance(full)
    assert (sem[:100] == 10).all() and (inst[:100] == 3).all()  # car
    assert (sem[100:150] == 51).all() and (inst[100:150] == 0).all()  # fence, no instance
    assert (sem[150:] == 40).all()  # road
    assert thing_mask(full).sum() == 100


def _write_pcap(path: Path, payloads: list[bytes], port: int) -> None:
    import dpkt

    with open(path, "wb") as f:
        w = dpkt.pcap.Writer(f)
        for k, data in enumerate(payloads):
            udp = dpkt.udp.UDP(sport=7502, dport=port, data=data)
            udp.ulen = len(udp)
            ip = dpkt.ip.IP(src=b"\x0a\0\0\1", dst=b"\x0a\0\0\2", p=17, data=udp)
            ip.len = len(ip)
            w.writepkt(bytes(dpkt.ethernet.Ethernet(data=ip)), ts=k * 1e-3)


def test_frames_count_complete_revolutions_inside_a_pcap(tmp_path: Path) -> None:
    """A capture that starts and ends mid-revolution: the partial revolutions are left out,
    ``--frames`` counts the complete ones from 0 inside the file."""
    meta = _meta("RNG19_RFL8_SIG16_NIR16")
    rng = np.random.default_rng(5)
    images = [
        rng.integers(1, 60_000, (meta.beams, meta.columns)).astype(np.uint32) for _ in range(4)
    ]
    packets = []
    for k, img in enumerate(images):
        pk = _packets(meta, img, 5 + k)
        packets += pk[2:] if k == 0 else pk[:1] if k == 3 else pk  # cut first and last turns
    d = tmp_path / "in"
    d.mkdir()
    _write_pcap(d / "rec.pcap", packets, 7502)
    (d / "rec.json").write_text(json.dumps(_ouster_json(meta)))
    ds = open_dataset(d / "rec.pcap")
    assert [r.frame for r in ds.refs()] == [0, 1]
    assert len(ds.infos["rec"].partial) == 2
    for k, ref in enumerate(ds.refs()):
        frame = ds.load(ref)
        expect = (destagger(images[k + 1], meta.pixel_shift) * 0.001).astype(np.float32)
        np.testing.assert_array_equal(frame.image.ranges, expect)
    (only,) = open_dataset(d / "rec.pcap", frames=(1, 2)).refs()
    assert only.frame == 1


def test_ouster_image_azimuths_match_the_points(shared_data: Path) -> None:
    """With the per-row azimuth offsets, every valid pixel's azimuth is its point's azimuth
    (far points, where the 14 mm beam origin offset does not matter) to a fraction of a
    column."""
    ds = open_dataset(shared_data / SENSORS / (OS2 + ".pcap"))
    frame = ds.load(ds.refs()[0])
    image = frame.image
    assert image.has_azimuth_offset and image.one_point_per_pixel
    far = np.linalg.norm(frame.points, axis=1) > 10
    az_pix = image.pixel_azimuth().reshape(-1)[image.point_pixel[far]]
    az_pts = np.arctan2(frame.points[far, 1], frame.points[far, 0])
    d = np.abs(np.angle(np.exp(1j * (az_pix - az_pts))))
    step = 2 * np.pi / image.shape[1]
    assert np.percentile(d, 99) < 0.1 * step and d.max() < 0.5 * step


def _velodyne_capture(tmp_path: Path, model: str) -> tuple[Path, np.ndarray, np.ndarray]:
    """A pcap of 2.3 turns of ``model``'s packets (tests/velodyne_packets.py) from known
    ranges: unique per firing and laser, 10 % without return. Returns the pcap, the ranges
    (F, lasers) and the firings' azimuths (0.01 deg)."""
    from velodyne_packets import MODELS, write_packets

    lasers, _, _, res = MODELS[model]
    step = 40  # 0.4 deg per firing: 900 firings per turn
    firings = int(2.3 * 36000 / step)
    rng = np.random.default_rng(lasers)
    ranges = (np.rint(rng.uniform(1.0, 60.0, (firings, lasers)) / res) * res).astype(np.float64)
    ranges[rng.random(ranges.shape) < 0.1] = 0.0
    azimuth = np.arange(firings) * step + 1234
    d = tmp_path / "in"
    d.mkdir(exist_ok=True)
    path = d / f"{model}.pcap"
    _write_pcap(path, write_packets(model, azimuth, ranges), 2368)
    return path, ranges, azimuth


@pytest.mark.parametrize("model", ["HDL32E", "VLP32C", "HDL64E"])
def test_velodyne_models_from_written_packets(tmp_path: Path, model: str) -> None:
    """HDL-32E, VLP-32C and HDL-64E packets written per Velodyne's layout from known ranges,
    read by flic (the HDL-64E with velodyne-decoder's bundled S3 calibration): rows = the
    beams, top beam first; every return a point in its own pixel, no pixel without one; per
    laser, the image row holds exactly the ranges written for it, firing after firing (the
    rings and the firing order round-trip); each point at its laser's elevation."""
    import velodyne_decoder as vd

    path, ranges, _ = _velodyne_capture(tmp_path, model)
    lasers = ranges.shape[1]
    reader = {}
    if model == "HDL64E":
        calib = tmp_path / "hdl64e.yml"
        vd.get_bundled_calibration("HDL-64E_S3-VeloView.yml").write(str(calib))
        reader = {"calibration": calib}
    ds = open_dataset(path, reader=reader)
    refs = ds.refs()
    assert ds.format == "velodyne" and len(refs) == 2  # 2.3 turns: 2 complete
    sensor = ds.sensor(refs[0])
    assert sensor.beams == lasers and np.all(np.diff(sensor.elevation) < 0)  # row 0 = top
    cal = ds.infos[model].state.sensor.calibration()
    row_of_laser = np.argsort(np.argsort(-cal["vert_correction"], kind="stable"), kind="stable")
    total = 0
    for ref in refs:
        frame = ds.load(ref)
        image = frame.image
        w = image.shape[1]
        assert image.shape[0] == lasers and image.one_point_per_pixel
        assert np.count_nonzero(image.ranges) == frame.points.shape[0]
        total += frame.points.shape[0]
        row = image.point_pixel // w
        el = np.arctan2(frame.points[:, 2], np.linalg.norm(frame.points[:, :2], axis=1))
        # a laser's vertical origin offset (HDL-64E calibration: up to 0.25 m) tilts near points
        offset = np.abs(cal["vert_offset_correction"]).max() if model == "HDL64E" else 0.02
        tol = 0.3 + np.degrees(offset / np.linalg.norm(frame.points, axis=1))
        assert np.all(np.degrees(np.abs(el - image.elevation[row])) < tol)
        # every pixel (row of laser L, column c) holds a range written for laser L at a firing
        # f with c = f + S mod W, one S for the whole frame: rings and firing order round-trip.
        # |xyz| is the range from the lasers' common origin: within 3 cm; the HDL-64E's adds
        # the laser's dist_correction (and its x/y and focal corrections: within 30 cm)
        near = 0.3 if model == "HDL64E" else 0.03
        shifts = []
        for laser in range(lasers):
            got = image.ranges[row_of_laser[laser]]
            expect = ranges[:, laser] + (cal["dist_correction"][laser] if model == "HDL64E" else 0)
            cols = np.flatnonzero(got)
            for c, v in zip(cols.tolist(), got[cols].tolist(), strict=True):
                f = np.flatnonzero((np.abs(expect - v) < near) & (ranges[:, laser] > 0))
                assert f.size, (laser, c, v)
                shifts.append(set(((c - f) % w).tolist()))
        common = set.intersection(*shifts)
        assert len(common) >= 1, "no single firing -> column shift"
    # every written return is a point of a frame or of the remainder left out
    remainder = sum(int(p.split()[2].replace(",", "")) for p in ds.infos[model].partial)
    assert total + remainder == np.count_nonzero(ranges)


def test_hdl64e_without_calibration_names_the_option(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """HDL-64E packets carry no product id and this capture no calibration in its status
    bytes: one line naming --calibration, exit 2; a file velodyne-decoder cannot read is one
    line too."""
    path, _, _ = _velodyne_capture(tmp_path, "HDL64E")
    code, _, err = _cli(["info", path], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "unknown Velodyne model" in err and "--calibration FILE" in err
    bad = tmp_path / "bad.yml"
    bad.write_text("lasers: [1, 2\n")
    code, _, err = _cli(["info", path, "--calibration", bad], capsys)
    assert code == 2 and "is not a velodyne-decoder calibration" in err, err
    code, _, err = _cli(["info", path, "--calibration", tmp_path / "none.yml"], capsys)
    assert code == 2 and "is no file" in err, err


def test_organised_pcd_keeps_its_rows_and_columns(tmp_path: Path) -> None:
    """An organised cloud (HEIGHT rows of WIDTH points, NaN where no return, no ring field):
    the image is HEIGHT x WIDTH, every point in the pixel of its row and its azimuth's column."""
    from pypcd4 import MetaData, PointCloud

    xyz, ring, az = _ring_cloud(16, 900)
    order = np.lexsort((-az, -ring))  # top ring first, azimuth decreasing along the row
    xyz, ring, az = xyz[order], ring[order], az[order]
    gone = np.random.default_rng(2).random(xyz.shape[0]) < 0.1
    xyz[gone] = np.nan
    data = np.empty(xyz.shape[0], dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
    data["x"], data["y"], data["z"] = xyz.T
    meta = MetaData.model_validate(
        {"fields": ("x", "y", "z"), "size": (4, 4, 4), "type": ("F", "F", "F"),
         "count": (1, 1, 1), "points": xyz.shape[0], "width": 900, "height": 16}
    )  # fmt: skip
    path = tmp_path / "organised.pcd"
    PointCloud(meta, data).save(path)
    ds = open_dataset(path)
    frame = ds.load(ds.refs()[0])
    assert frame.image.shape == (16, 900) and frame.n_read == 16 * 900
    assert frame.points.shape[0] == int((~gone).sum())
    expect = (15 - ring) * 900 + np.floor((np.pi - az) / (2 * np.pi) * 900).astype(int) % 900
    np.testing.assert_array_equal(frame.image.point_pixel, expect[~gone])


@pytest.mark.slow
def test_osf_frames_equal_the_pcap_frames(shared_data: Path, tmp_path: Path) -> None:
    """An OSF written by ouster-sdk from the OS-2-128 pcap (where ouster-sdk is installed in
    flic's environment) reads to the same image and points as the pcap."""
    pytest.importorskip("ouster.sdk")
    import subprocess
    import sys

    src = shared_data / SENSORS
    osf = tmp_path / "in" / "os2.osf"
    osf.parent.mkdir()
    cli = Path(sys.executable).with_name("ouster-cli")
    subprocess.run(
        [cli, "source", "-m", src / (OS2 + ".json"), src / (OS2 + ".pcap"), "save", osf],
        check=True,
        capture_output=True,
    )
    ds = open_dataset(osf)
    assert ds.format == "osf"
    a = ds.load(ds.refs()[0])
    pcap = open_dataset(src / (OS2 + ".pcap"))
    b = pcap.load(pcap.refs()[0])
    np.testing.assert_array_equal(a.image.ranges, b.image.ranges)
    np.testing.assert_allclose(a.points, b.points, atol=1e-4)


def test_osf_without_ouster_sdk_names_the_extra(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import importlib.util

    try:
        if importlib.util.find_spec("ouster") is not None:
            pytest.skip("ouster-sdk is installed")
    except ModuleNotFoundError:
        pass
    d = tmp_path / "in"
    d.mkdir()
    (d / "x.osf").write_bytes(b"\0" * 64)
    line = _bad(["segment", d / "x.osf"], capsys, tmp_path / "o", "x.osf")
    assert "pip install --no-deps ouster-sdk" in line
