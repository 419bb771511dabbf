"""Test helpers: PointCloud2 messages of any layout and bags of them, written with rosbags."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

CODES = {"i1": 1, "u1": 2, "i2": 3, "u2": 4, "i4": 5, "u4": 6, "f4": 7, "f8": 8}


def store() -> Any:
    from flic_cli.io.bag import typestore

    return typestore()


def cloud_msg(
    st: Any,
    columns: dict[str, np.ndarray],
    types: dict[str, str] | None = None,
    *,
    bigendian: bool = False,
    gap: int = 0,
    height: int = 1,
    row_pad: int = 0,
    stamp_ns: int = 1_000_000_000,
    frame_id: str = "lidar",
    order: list[str] | None = None,
) -> Any:
    """A PointCloud2 with the given columns, each of numpy type ``types[name]`` (default f4),
    ``gap`` padding bytes after every field, ``row_pad`` bytes after every row, in ``order``."""
    names = order or list(columns)
    types = types or {}
    e = ">" if bigendian else "<"
    offsets, off = {}, 0
    for name in names:
        offsets[name] = off
        off += np.dtype(types.get(name, "f4")).itemsize + gap
    step = off
    dtype = np.dtype(
        {
            "names": names,
            "formats": [e + types.get(n, "f4") for n in names],
            "offsets": [offsets[n] for n in names],
            "itemsize": step,
        }
    )
    n = len(next(iter(columns.values())))
    arr = np.zeros(n, dtype=dtype)
    for name in names:
        arr[name] = columns[name]
    width = n // height
    rows = arr.view(np.uint8).reshape(height, width * step)
    data = np.concatenate([rows, np.full((height, row_pad), 0xAB, np.uint8)], axis=1).reshape(-1)
    t = st.types
    fields = [
        t["sensor_msgs/msg/PointField"](
            name=nm, offset=offsets[nm], datatype=CODES[types.get(nm, "f4")], count=1
        )
        for nm in names
    ]
    header = t["std_msgs/msg/Header"](
        stamp=t["builtin_interfaces/msg/Time"](
            sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000
        ),
        frame_id=frame_id,
    )
    return t["sensor_msgs/msg/PointCloud2"](
        header=header,
        height=height,
        width=width,
        fields=fields,
        is_bigendian=bigendian,
        point_step=step,
        row_step=width * step + row_pad,
        data=data,
        is_dense=False,
    )


def write_bag(path: Path, kind: str, messages: list[tuple[str, str, int, Any]]) -> Path:
    """Write ``(topic, msgtype, time_ns, msg)`` messages as ``kind``: ``ros1`` (a .bag),
    ``sqlite3`` or ``mcap`` (a rosbag2 folder); returns what to open."""
    st = store()
    if kind == "ros1":
        from rosbags.rosbag1 import Writer

        with Writer(path) as w:
            conns: dict[str, Any] = {}
            for topic, msgtype, t, msg in messages:
                if topic not in conns:
                    conns[topic] = w.add_connection(topic, msgtype, typestore=st)
                w.write(conns[topic], t, st.serialize_ros1(msg, msgtype))
        return path
    from rosbags.rosbag2 import StoragePlugin, Writer

    plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as w:
        conns = {}
        for topic, msgtype, t, msg in messages:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, msgtype, typestore=st)
            w.write(conns[topic], t, st.serialize_cdr(msg, msgtype))
    return path


def vlp16_clouds(shared: Path, n: int = 4) -> list[np.ndarray]:
    """Real VLP-16 revolutions (velodyne-decoder's points of the shared nebula bag), as
    structured arrays x y z intensity time ring."""
    from flic_cli.io.bag import open_reader

    out = []
    reader = open_reader(shared / "sensors/velodyne/nebula_vlp16/1673400471837873222")
    try:
        from flic_cli.io import velodyne
        from flic_cli.io.bag import _velodyne_points

        for c, _, raw in reader.messages():
            msg = reader.deserialize(raw, c.msgtype)
            packets = [
                (p.stamp.sec + p.stamp.nanosec * 1e-9, np.asarray(p.data, np.uint8).tobytes())
                for p in msg.packets
            ]
            sensor = velodyne.detect_sensor([packets[0][1]])
            out.append(_velodyne_points(sensor, packets))
            if len(out) == n:
                break
    finally:
        reader.close()
    return out


def cycled_vlp16_bag(shared: Path, path: Path, n: int) -> Path:
    """A rosbag2 folder (MCAP) of ``n`` real VelodyneScan messages: the nebula bag's 4
    revolutions cycled, bag time 100 ms apart (raw messages copied, not re-serialised)."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    from flic_cli.io.bag import open_reader

    reader = open_reader(shared / "sensors/velodyne/nebula_vlp16/1673400471837873222")
    try:
        raws = [(c, raw) for c, _, raw in reader.messages()]
    finally:
        reader.close()
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection(raws[0][0].topic, raws[0][0].msgtype, typestore=store())
        for k in range(n):
            w.write(conn, 1_700_000_000_000_000_000 + k * 100_000_000, raws[k % len(raws)][1])
    return path


#: ouster-ros's PointCloud2 point (PointOS, 48 bytes): name, offset, datatype code, numpy type.
OUSTER_ROS_LAYOUT = [
    ("x", 0, 7, "<f4"), ("y", 4, 7, "<f4"), ("z", 8, 7, "<f4"), ("intensity", 16, 7, "<f4"),
    ("t", 20, 6, "<u4"), ("reflectivity", 24, 4, "<u2"), ("ring", 26, 4, "<u2"),
    ("ambient", 28, 4, "<u2"), ("range", 32, 6, "<u4"),
]  # fmt: skip


def ouster_ros_cloud(st: Any, frame: Any, stamp_ns: int = 1_650_000_000_000_000_000) -> Any:
    """A decoded Ouster frame (its destaggered image and points) as ouster-ros publishes it:
    organised H x W, ring 0 = top beam, pixels without a return at the origin."""
    h, w = frame.image.shape
    dtype = np.dtype(
        {"names": [n for n, *_ in OUSTER_ROS_LAYOUT], "formats": [f for *_, f in OUSTER_ROS_LAYOUT],
         "offsets": [o for _, o, *_ in OUSTER_ROS_LAYOUT], "itemsize": 48}
    )  # fmt: skip
    cloud = np.zeros(h * w, dtype=dtype)
    pix = frame.image.point_pixel
    for j, c in enumerate("xyz"):
        cloud[c][pix] = frame.points[:, j]
    cloud["ring"] = np.repeat(np.arange(h), w)
    cloud["t"] = np.tile(np.arange(w) * (100_000_000 // w), h)
    cloud["intensity"][pix] = np.arange(pix.size) % 255
    t = st.types
    fields = [t["sensor_msgs/msg/PointField"](name=n, offset=o, datatype=d, count=1)
              for n, o, d, _ in OUSTER_ROS_LAYOUT]  # fmt: skip
    header = t["std_msgs/msg/Header"](
        stamp=t["builtin_interfaces/msg/Time"](sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9),
        frame_id="os_sensor",
    )
    return t["sensor_msgs/msg/PointCloud2"](
        header=header, height=h, width=w, fields=fields, is_bigendian=False, point_step=48,
        row_step=48 * w, data=cloud.view(np.uint8), is_dense=False,
    )  # fmt: skip
