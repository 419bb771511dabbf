"""Peak memory of ``flic segment BAG --export mcap`` against the bag's length.

Writes ROS 2 bags (MCAP storage, rosbags' writer) of N revolutions from the real recording
(the 4 VelodyneScan messages of tier4/nebula's VLP-16 bag, ``../shared/data/sensors``, cycled,
bag time 100 ms apart), then runs ``flic segment BAG --method flic14 --export mcap`` on each in a
subprocess of its own and reads the subprocess's peak resident memory (``ru_maxrss`` of
``resource.getrusage(RUSAGE_CHILDREN)``, one child per measurement: ``/usr/bin/time``-like).

Usage::

    python scripts/bags/bag_memory.py --lengths 20,2000 --out results/bags/memory.csv
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

NEBULA = Path(__file__).resolve().parents[3] / "shared/data/sensors/velodyne/nebula_vlp16"


def write_bag(path: Path, n: int) -> Path:
    """A rosbag2 folder (MCAP) of ``n`` VelodyneScan messages cycled from the nebula bag."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    from flic_cli.io.bag import open_reader

    reader = open_reader(NEBULA / "1673400471837873222")
    try:
        raws = [(c, raw) for c, _, raw in reader.messages()]
    finally:
        reader.close()
    conn0 = raws[0][0]
    t0 = 1_700_000_000_000_000_000
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        from flic_cli.io.bag import typestore

        conn = w.add_connection(conn0.topic, conn0.msgtype, typestore=typestore())
        for k in range(n):
            w.write(conn, t0 + k * 100_000_000, raws[k % len(raws)][1])
    return path


def peak_rss_mb(args: list[str]) -> tuple[float, float]:
    """Run ``args`` in a child that reports its own peak RSS; (peak MB, seconds)."""
    code = (
        "import resource, subprocess, sys, time; t = time.perf_counter(); "
        "r = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
        "el = time.perf_counter() - t; "
        "sys.stderr.write(r.stderr[-2000:]); assert r.returncode == 0, r.returncode; "
        "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, el)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, check=True
    )
    mb, seconds = out.stdout.split()
    return float(mb), float(seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lengths", default="20,2000", help="revolutions per bag")
    parser.add_argument("--out", type=Path, default=None, help="CSV of the figures")
    parser.add_argument("--keep", type=Path, default=None, help="folder for the bags (kept)")
    args = parser.parse_args()
    flic = shutil.which("flic") or "flic"
    work = Path(args.keep or tempfile.mkdtemp(prefix="flic-bag-memory-"))
    rows = []
    for n in (int(x) for x in args.lengths.split(",")):
        bag = work / f"vlp16_{n}"
        if not bag.exists():
            t = time.perf_counter()
            write_bag(bag, n)
            print(f"wrote {bag} ({n} revolutions) in {time.perf_counter() - t:.1f} s")
        size = sum(p.stat().st_size for p in bag.iterdir())
        out = work / f"out_{n}"
        shutil.rmtree(out, ignore_errors=True)
        mb, seconds = peak_rss_mb(
            [flic, "segment", str(bag), "--method", "flic14", "--export", "mcap",
             "--out", str(out)]
        )  # fmt: skip
        exported = sum(p.stat().st_size for p in out.glob("*_flic_mcap/*"))
        rows.append(
            {"revolutions": n, "bag_mb": size / 2**20, "peak_rss_mb": mb, "seconds": seconds,
             "export_mb": exported / 2**20}
        )  # fmt: skip
        print(rows[-1])
        if args.keep is None:
            shutil.rmtree(out, ignore_errors=True)
    table = pd.DataFrame(rows)
    print(table.to_string(index=False))
    if args.out is not None:
        from flic_cli.io.atomic import write_table

        write_table(args.out, table)
    if args.keep is None:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
