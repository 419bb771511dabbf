"""Reading a PointCloud2 of 131,072 points into a range image: time per stage, one core.

The cloud is the real OS-2-128 revolution of ``../shared/data/sensors/ouster`` (its pcap,
decoded by flic's Ouster reader) written as ouster-ros publishes it: organised 128 x 1024,
48-byte points (x y z at 0/4/8, intensity f4 at 16, t u4 at 20, reflectivity u2 at 24, ring u2
at 26, ambient u2 at 28, range u4 at 32; ring 0 = top beam), pixels without a return at the
origin, one message in a ROS 2 bag (MCAP storage). Stages, each timed ``--repeat`` times (median,
p90):

- ``deserialize``: rosbags' CDR deserialisation of the message (the bag reader's first step);
- ``cloud_to_image``: PointCloud2 message -> range image: the structured view of ``data``
  (:func:`flic_cli.io.pointcloud2.cloud_array`), x/y/z, the ring field, the ring image
  (:func:`flic_cli.io.pointcloud2.ring_image`), as :class:`flic_cli.io.bag.BagDataset` does;
- ``load``: :meth:`BagDataset.load` end to end (storage read + the two above + frame).

Also compares the image with the pcap reader's own (destaggered) image of the same revolution:
rows, valid pixels, the pcap's valid pixels that are valid at the same row and column here.

Usage (one core)::

    NUMBA_NUM_THREADS=1 taskset -c 0 python scripts/bags/cloud_speed.py --repeat 300
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

SHARED = Path(__file__).resolve().parents[3] / "shared/data/sensors/ouster"
PCAP = SHARED / "OS-2-128-U1_v2.3.0_1024x10.pcap"
LAYOUT = [  # name, offset, datatype code, numpy type
    ("x", 0, 7, "<f4"), ("y", 4, 7, "<f4"), ("z", 8, 7, "<f4"), ("intensity", 16, 7, "<f4"),
    ("t", 20, 6, "<u4"), ("reflectivity", 24, 4, "<u2"), ("ring", 26, 4, "<u2"),
    ("ambient", 28, 4, "<u2"), ("range", 32, 6, "<u4"),
]  # fmt: skip
STEP = 48


def ouster_cloud(store, stamp_ns: int = 1_650_000_000_000_000_000):  # noqa: ANN001, ANN201
    """The pcap's revolution as an ouster-ros PointCloud2, and the pcap reader's frame."""
    from flic_cli.io import open_dataset

    ds = open_dataset(PCAP)
    frame = ds.load(ds.refs()[0])
    h, w = frame.image.shape
    dtype = np.dtype(
        {"names": [n for n, *_ in LAYOUT], "formats": [f for *_, f in LAYOUT],
         "offsets": [o for _, o, *_ in LAYOUT], "itemsize": STEP}
    )  # fmt: skip
    cloud = np.zeros(h * w, dtype=dtype)
    pix = frame.image.point_pixel
    for j, c in enumerate("xyz"):
        cloud[c][pix] = frame.points[:, j]
    cloud["ring"] = np.repeat(np.arange(h), w)
    cloud["t"] = np.tile(np.arange(w) * (100_000_000 // w), h)
    cloud["range"][pix] = np.round(frame.image.ranges.reshape(-1)[pix] * 1000).astype(np.uint32)
    cloud["intensity"][pix] = 100.0
    t = store.types
    fields = [t["sensor_msgs/msg/PointField"](name=n, offset=o, datatype=d, count=1)
              for n, o, d, _ in LAYOUT]  # fmt: skip
    header = t["std_msgs/msg/Header"](
        stamp=t["builtin_interfaces/msg/Time"](sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9),
        frame_id="os_sensor",
    )
    msg = t["sensor_msgs/msg/PointCloud2"](
        header=header, height=h, width=w, fields=fields, is_bigendian=False, point_step=STEP,
        row_step=STEP * w, data=cloud.view(np.uint8), is_dense=False,
    )  # fmt: skip
    return msg, frame


def _times(func, repeat: int) -> np.ndarray:  # noqa: ANN001
    out = np.empty(repeat)
    for k in range(repeat):
        t0 = time.perf_counter_ns()
        func()
        out[k] = (time.perf_counter_ns() - t0) / 1e6
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=300)
    args = parser.parse_args()

    from rosbags.rosbag2 import StoragePlugin, Writer

    from flic_cli.io import open_dataset
    from flic_cli.io.bag import BagDataset, typestore
    from flic_cli.io.pointcloud2 import cloud_array, ring_image, xyz_of

    store = typestore()
    msg, pcap_frame = ouster_cloud(store)
    raw = bytes(store.serialize_cdr(msg, "sensor_msgs/msg/PointCloud2"))
    bag = Path(tempfile.mkdtemp(prefix="flic-cloud-speed-")) / "ouster"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection("/ouster/points", "sensor_msgs/msg/PointCloud2", typestore=store)
        w.write(conn, 1, raw)
    ds = open_dataset(bag)
    assert isinstance(ds, BagDataset)
    beams = ds.beams

    def to_image() -> None:
        cloud = cloud_array(msg)
        xyz = xyz_of(cloud, bag, "/ouster/points")
        ring_image(xyz, cloud["ring"], beams)

    ref = ds.refs()[0]
    stages = {
        "deserialize": lambda: store.deserialize_cdr(raw, "sensor_msgs/msg/PointCloud2"),
        "cloud_to_image": to_image,
        "load": lambda: ds.load(ref),
    }
    for f in stages.values():  # warm-up: numba cache, first imports
        f()
    print(f"cloud: {msg.height} x {msg.width} = {msg.height * msg.width:,} points, "
          f"{len(raw):,} bytes; {args.repeat} runs per stage")  # fmt: skip
    for name, f in stages.items():
        ms = _times(f, args.repeat)
        print(f"{name:>15}: median {np.median(ms):.3f} ms, p90 {np.percentile(ms, 90):.3f} ms")
    frame = ds.load(ref)
    a, b = frame.image.ranges, pcap_frame.image.ranges
    both = (a > 0) & (b > 0)
    print(f"rows {a.shape[0]} (pcap {b.shape[0]}), columns {a.shape[1]} (pcap {b.shape[1]}); "
          f"points read {frame.points.shape[0]:,} (pcap valid {pcap_frame.points.shape[0]:,}); "
          f"valid pixels {np.count_nonzero(a):,} (pcap {np.count_nonzero(b):,}); "
          f"pcap's valid pixels valid here too {np.mean(a[b > 0] > 0):.4f}; range (|xyz|, "
          f"beam origin offsets included) minus the pcap's range: median "
          f"{1000 * np.median(a[both] - b[both]):.1f} mm")  # fmt: skip


if __name__ == "__main__":
    main()
