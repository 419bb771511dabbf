"""Every method on every shared sensor recording through the API: one label per point.

    python scripts/sensors/check_formats.py --out results/sensors/formats_check.csv

For each recording of ../shared/data/sensors (Ouster, Velodyne, PCD, nuScenes) and each method
variant the config runs by default (``--methods all``: every variant but the per-class ALPINE
ones, which need semantic classes): the frame's points as stored, the labels returned (must be one
per point), clusters, and the seconds the call took (first call per method includes numba's
cache load; the machine was shared, so these are no benchmark).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd
from recordings import RECORDINGS, ROOT, SENSORS  # scripts/sensors/recordings.py

import flic_cli.api as flic


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "results/sensors/formats_check.csv")
    parser.add_argument(
        "--methods",
        default=None,
        help="comma-separated, or `all`; default: the config's default_methods (those `flic "
        "evaluate` runs)",
    )
    args = parser.parse_args()
    if args.methods == "all":  # per-class ALPINE needs semantic classes: a recording has none
        methods = [m for m in flic.methods() if m not in ("alpine", "alpine-k32")]
    elif args.methods:
        methods = args.methods.split(",")
    else:
        from flic_cli.config import load_config

        methods = list(load_config().default_methods)
    rows = []
    for rec in RECORDINGS:
        frame = flic.load_frame(SENSORS / rec)
        for method in methods:
            start = time.perf_counter()
            labels = flic.segment_frame(frame, method)
            seconds = time.perf_counter() - start
            rows.append(
                {
                    "recording": rec,
                    "format": frame.ref.format,
                    "image": "x".join(map(str, frame.image.shape)),
                    "method": method,
                    "points_stored": frame.n_read,
                    "labels": labels.shape[0],
                    "one_label_per_point": labels.shape[0] == frame.n_read,
                    "clusters": int(np.unique(labels[labels > 0]).size),
                    "seconds": round(seconds, 3),
                }
            )
            print(rows[-1], flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame(rows).to_csv(args.out, index=False)


if __name__ == "__main__":
    main()
