"""What holding the feet out costs: each method with its own remover, ``column`` with step 8
(``hold_feet``, the default) against ``column`` without it, timed as ``flic benchmark`` times a
method (a freshly read and projected frame, then one call of ground step and clusterer), the two
alternating from frame to frame so that both see the same machine load.

Writes one row per (data set, method): the medians over frames and rounds, their difference and
ratio.

Usage::

    python scripts/hold_cost.py /tmp/flic-kitti-log ../shared/data/semantickitti \\
        --methods flic0,flic14,flic14n,bridge --out results/ground/speed_hold_feet.csv
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.runs.pipeline import build_segmenter, prepare


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="+", type=Path)
    parser.add_argument("--methods", default="flic0,flic14,flic14n,bridge")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()

    cfg = load_config()
    rows = []
    for root in args.data:
        ds = open_dataset(root)
        refs = ds.refs()
        for name in args.methods.split(","):
            seg = build_segmenter(cfg, name, "ground", "own")
            off = dataclasses.replace(seg.remover, hold_feet=False)
            pair = {"hold_feet": seg, "without": dataclasses.replace(seg, remover=off)}
            warm = prepare(ds.load(refs[0]), "ground", cfg.projection)
            for s in pair.values():
                s(warm.image, warm.points)  # JIT, caches
            times: dict[str, list[float]] = {k: [] for k in pair}
            for rnd in range(args.rounds):
                for i, ref in enumerate(refs):
                    order = list(pair) if (i + rnd) % 2 == 0 else list(pair)[::-1]
                    for key in order:
                        prep = prepare(ds.load(ref), "ground", cfg.projection)
                        t0 = time.perf_counter()
                        pair[key](prep.image, prep.points)
                        times[key].append(time.perf_counter() - t0)
            held, without = (1e3 * float(np.median(times[k])) for k in ("hold_feet", "without"))
            row = {"data": root.name, "method": name, "frames": len(refs),
                   "rounds": args.rounds, "ms_hold_feet": round(held, 4),
                   "ms_without": round(without, 4), "diff_ms": round(held - without, 4),
                   "ratio": round(held / without, 3)}  # fmt: skip
            print(row, flush=True)
            rows.append(row)
    df = pd.DataFrame(rows)
    print(df.to_string(index=False))
    if args.out is not None:
        write_table(args.out, df)


if __name__ == "__main__":
    main()
