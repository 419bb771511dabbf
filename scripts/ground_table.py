"""The ground table: every ground remover on a labelled data set, with the clusterers' IoU_mu.

Per remover, over all frames of the ground setting (every point of the scan projected):
precision, recall and F1 of its ground decision against the ground classes, the share of
thing-object points it removes (:mod:`flic_cli.metrics.ground`), and its median time per frame
(the remover alone with its per-point decisions, :func:`flic_cli.ground.base.extract_ground`;
single-threaded kernels, after a warm-up, ``--repeat`` calls per frame, the median kept).
With ``--evaluate REMOVER=DIR``, the IoU_mu of every method in the ground and no-ground settings
are read from ``DIR/table.csv`` of a ``flic evaluate --setting both --ground-remover REMOVER`` run
and added as ``iou_ground_METHOD`` / ``gap_METHOD`` (no-ground minus ground) columns.

Usage::

    python scripts/ground_table.py ../shared/data/semantickitti \\
        --evaluate column=/tmp/ev_column --evaluate paper=/tmp/ev_paper \\
        --out results/ground/table.csv
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.config import load_config
from flic_cli.ground.base import extract_ground
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.metrics.ground import GroundCounts, ground_counts, ground_scores
from flic_cli.runs.pipeline import prepare


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default="../shared/data/semantickitti", type=Path)
    parser.add_argument("--removers", default="paper,bogoslavskyi,column,patchworkpp")
    parser.add_argument("--evaluate", action="append", default=[], metavar="REMOVER=DIR")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", type=Path, default=Path("results/ground/table.csv"))
    args = parser.parse_args()

    cfg = load_config()
    ds = open_dataset(args.data)
    frames = [prepare(ds.load(ref), "ground", cfg.projection) for ref in ds.refs()]
    evaluated = dict(item.split("=", 1) for item in args.evaluate)
    rows = []
    for name in args.removers.split(","):
        remover = cfg.remover(name)
        extract_ground(remover, frames[0].image, frames[0].points)  # warm-up (JIT, caches)
        counts = GroundCounts()
        times = []
        for prep in frames:
            per_call = []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                ground = extract_ground(remover, prep.image, prep.points)
                per_call.append(time.perf_counter() - t0)
            times.append(float(np.median(per_call)))
            counts = counts + ground_counts(prep.labels, ground.on_ground)
        row = {"remover": name}
        row.update({k: round(v, 2) for k, v in ground_scores(counts).items()})
        row["ms_per_frame"] = round(1000 * float(np.median(times)), 3)
        if name in evaluated:
            table = pd.read_csv(Path(evaluated[name]) / "table.csv")
            for _, t in table.iterrows():
                row[f"iou_ground_{t['method']}"] = t["iou_mu_ground"]
                row[f"gap_{t['method']}"] = round(t["iou_mu_no_ground"] - t["iou_mu_ground"], 2)
        rows.append(row)
        print(row, flush=True)
    df = pd.DataFrame(rows)
    write_table(args.out, df)
    print(df.T.to_string(header=False))


if __name__ == "__main__":
    main()
