"""Time the ground removers alone, interleaved frame by frame, on one data set.

Every frame is read and projected once; then each round calls every remover once per frame, in
turn, so that all removers see the same machine load. Prints (and optionally writes) the median,
p5 and p95 milliseconds per frame and each remover's median relative to the first one. Removers
that need points get the frame's points. Timings on a shared machine are noisy: compare the
relative figures of one run, not absolute figures across runs.

Usage::

    python scripts/ground_speed.py /tmp/s/moosmann --removers paper,column,bogoslavskyi \\
        --rounds 5 --out results/ground/speed_removers_moosmann.csv
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.runs.pipeline import prepare


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("--removers", default="paper,column,bogoslavskyi")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=None, help="first N frames only")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()

    cfg = load_config()
    ds = open_dataset(args.data)
    frames = [prepare(ds.load(ref), "ground", cfg.projection) for ref in ds.refs()]
    frames = frames[: args.frames]
    names = args.removers.split(",")
    removers = {n: cfg.remover(n) for n in names}
    for remover in removers.values():  # warm-up: JIT compilation or cache load
        remover(frames[0].image, frames[0].points)
    times: dict[str, list[float]] = {n: [] for n in names}
    for _ in range(args.rounds):
        for prep in frames:
            for n, remover in removers.items():
                t0 = time.perf_counter()
                remover(prep.image, prep.points)
                times[n].append(time.perf_counter() - t0)
    h, w = frames[0].image.ranges.shape
    base = float(np.median(times[names[0]]))
    rows = [
        {
            "remover": n,
            "image": f"{w}x{h}",
            "calls": len(t),
            "median_ms": round(1000 * float(np.median(t)), 4),
            "p5_ms": round(1000 * float(np.percentile(t, 5)), 4),
            "p95_ms": round(1000 * float(np.percentile(t, 95)), 4),
            f"median_vs_{names[0]}": round(float(np.median(t)) / base, 2),
        }
        for n, t in times.items()
    ]
    df = pd.DataFrame(rows)
    print(df.to_string(index=False))
    if args.out is not None:
        write_table(args.out, df)


if __name__ == "__main__":
    main()
