"""Reading + range image per shared sensor recording: median of many repeats on one core.

    python scripts/sensors/read_timing.py --repeat 200 --out results/sensors/read_timing.csv

Times ``dataset.load(ref)`` (file read, packet decoding, destaggering / ring and column
assignment, the range image and the points), after one warm-up load, pinned to one CPU core, and
beside it the bare library call it is built on, measured interleaved in the same run (the
"peer"): velodyne-decoder's own ``read_pcap`` of the same file, pypcd4's ``PointCloud.from_path``,
numpy's ``fromfile``; for Ouster, the dpkt pass over the capture (flic indexes it once at open,
so a load does not repeat it).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.io import open_dataset

ROOT = Path(__file__).resolve().parents[2]
SENSORS = ROOT.parent / "shared" / "data" / "sensors"


def _peer(rec: str):  # noqa: ANN202
    path = SENSORS / rec
    if rec.endswith(".pcap") and "velodyne" in rec:
        import velodyne_decoder as vd

        cfg = vd.Config(model=vd.Model.VLP16)
        return "velodyne_decoder.read_pcap (whole file)", lambda: list(vd.read_pcap(str(path), cfg))
    if rec.endswith(".pcap"):
        from flic_cli.io.pcap import index_udp

        return "dpkt pass over the capture (index_udp)", lambda: index_udp(path)
    if rec.endswith(".pcd"):
        from pypcd4 import PointCloud

        return "pypcd4 PointCloud.from_path", lambda: PointCloud.from_path(str(path)).pc_data
    return "numpy.fromfile", lambda: np.fromfile(path, dtype="<f4")


RECORDINGS = [
    "ouster/OS-2-128-U1_v2.3.0_1024x10.pcap",
    "ouster/OS-1-64_1024x10_fw20.pcap",
    "velodyne/vlp16_velodyne_example.pcap",
    "pcd/robosense_helios16p_1691031766781547066.pcd",
    "velodyne/nebula_vlp16/1673400472138016708.pcd",
    "nuscenes/n015-2018-07-24-11-22-45+0800__LIDAR_TOP__1532402927647951.pcd.bin",
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=200)
    parser.add_argument("--core", type=int, default=0)
    parser.add_argument("--out", type=Path, default=ROOT / "results/sensors/read_timing.csv")
    args = parser.parse_args()
    os.sched_setaffinity(0, {args.core})
    rows = []
    for rec in RECORDINGS:
        ds = open_dataset(SENSORS / rec)
        ref = ds.refs()[0]
        frame = ds.load(ref)  # warm-up (numba cache load, LUTs)
        peer_name, peer = _peer(rec)
        peer()
        ours, theirs = [], []
        for _ in range(args.repeat):  # interleaved: both see the same machine load
            t = time.perf_counter()
            ds.load(ref)
            ours.append(time.perf_counter() - t)
            t = time.perf_counter()
            peer()
            theirs.append(time.perf_counter() - t)
        rows.append(
            {
                "recording": rec,
                "format": ds.format,
                "image": "x".join(map(str, frame.image.shape)),
                "points": frame.points.shape[0],
                "load_ms_min": round(1e3 * float(np.min(ours)), 3),
                "load_ms_median": round(1e3 * float(np.median(ours)), 3),
                "load_ms_p10": round(1e3 * float(np.percentile(ours, 10)), 3),
                "load_ms_p90": round(1e3 * float(np.percentile(ours, 90)), 3),
                "peer": peer_name,
                "peer_ms_min": round(1e3 * float(np.min(theirs)), 3),
                "peer_ms_median": round(1e3 * float(np.median(theirs)), 3),
                "load_average_1min": round(os.getloadavg()[0], 1),
                "repeats": args.repeat,
            }
        )
        print(rows[-1], flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame(rows).to_csv(args.out, index=False)


if __name__ == "__main__":
    main()
