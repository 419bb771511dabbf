"""Reading + range image per shared sensor recording (and the nuScenes sweep of 34,688 points
written as a PCD in each encoding): median of many repeats on one core.

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
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from recordings import RECORDINGS, ROOT, SENSORS  # scripts/sensors/recordings.py

from flic_cli.io import open_dataset


def _peer(path: Path):  # noqa: ANN202
    rec = str(path)
    if rec.endswith(".pcap") and "velodyne" in rec:
        import velodyne_decoder as vd

        cfg = vd.Config(model=vd.Model.VLP16)
        return "velodyne_decoder.read_pcap (whole file)", lambda: list(vd.read_pcap(rec, cfg))
    if rec.endswith(".pcap"):
        from flic_cli.io.pcap import index_udp

        return "dpkt pass over the capture (index_udp)", lambda: index_udp(path)
    if rec.endswith(".pcd"):
        from pypcd4 import PointCloud

        return "pypcd4 PointCloud.from_path", lambda: PointCloud.from_path(rec).pc_data
    return "numpy.fromfile", lambda: np.fromfile(path, dtype="<f4")


def _encoding(path: Path) -> str:
    """What the reader parses: a PCD's DATA encoding, raw float32, or packets."""
    if path.suffix == ".pcd":
        with open(path, "rb") as f:
            for line in f:
                if line.startswith(b"DATA"):
                    return line.split()[1].decode()
    return "float32 records" if path.name.endswith(".pcd.bin") else "UDP packets"


def _pcd_copies(folder: Path) -> list[tuple[str, Path]]:
    """The nuScenes sweep (34,688 points: x y z intensity ring) written as a PCD in each of the
    three encodings, for the target's "PCD of 35k points"."""
    from pypcd4 import Encoding, PointCloud

    pts = np.fromfile(SENSORS / RECORDINGS[-1], dtype="<f4").reshape(-1, 5)
    cloud = PointCloud.from_points(
        [pts[:, 0], pts[:, 1], pts[:, 2], pts[:, 3], pts[:, 4].astype(np.uint16)],
        ("x", "y", "z", "intensity", "ring"),
        (np.float32, np.float32, np.float32, np.float32, np.uint16),
    )
    out = []
    for enc in (Encoding.ASCII, Encoding.BINARY, Encoding.BINARY_COMPRESSED):
        path = folder / f"nuscenes_sweep_{enc.value}.pcd"
        cloud.save(path, encoding=enc)
        out.append((f"(nuScenes sweep as {enc.value} PCD)", path))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=200)
    parser.add_argument("--core", type=int, default=0)
    parser.add_argument("--out", type=Path, default=ROOT / "results/sensors/read_timing.csv")
    args = parser.parse_args()
    os.sched_setaffinity(0, {args.core})
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        inputs = [(rec, SENSORS / rec) for rec in RECORDINGS] + _pcd_copies(Path(tmp))
        for rec, path in inputs:
            ds = open_dataset(path)
            ref = ds.refs()[0]
            frame = ds.load(ref)  # warm-up (numba cache load, LUTs)
            peer_name, peer = _peer(path)
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
                    "encoding": _encoding(path),
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
