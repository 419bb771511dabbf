"""Sweep the parameters of the ``column`` ground remover, one at a time around the defaults.

For every parameter value: the ground scores over all frames (precision, recall, F1 against the
ground classes, share of thing-object points removed; :mod:`flic_cli.metrics.ground`) and the
ground-setting IoU_mu of the clusterers with that mask, next to their no-ground IoU_mu (the
ground classes removed by label). Runs on a SemanticKITTI root (the shared frames) and on the
synthetic sample (written to a temporary folder), so that no parameter is chosen on one data set
alone. Writes one CSV row per (data set, parameter, value) and prints the table.

Usage::

    python scripts/ground_sweep.py ../shared/data/semantickitti \
        --out results/ground/sweep_column.csv
    python scripts/ground_sweep.py ... --methods flic0,flic6,flic14,dbscan   # DBSCAN: slow
    python scripts/ground_sweep.py ../shared/data/semantickitti \
        --params neighbour_px,neighbour_band_m,foot_deg,under_m,base_band_m \
        --methods flic0,flic6,flic14,bridge,dbscan-fast \
        --out results/ground/sweep_column_neighbours.csv
    python scripts/ground_sweep.py ../shared/data/semantickitti --params hold_feet,attach_m \
        --methods flic0,flic6,flic14,flic14n,bridge,dbscan-fast \
        --out results/ground/sweep_column_hold.csv
"""

from __future__ import annotations

import argparse
import tempfile
from dataclasses import fields
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.config import load_config
from flic_cli.ground import ColumnGround
from flic_cli.ground.base import Ground, extract_ground
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.metrics import match_objects
from flic_cli.metrics.ground import GroundCounts, ground_counts, ground_scores
from flic_cli.runs.pipeline import cluster_ground, prepare

#: Values tried per parameter (the default is always included).
GRID: dict[str, list[float]] = {
    "noise_m": [0.02, 0.03, 0.05, 0.08],
    "slope_change_deg": [0.5, 1.0, 2.0, 3.0],
    "kerb_m": [0.1, 0.15, 0.2, 0.25],
    "max_step_m": [0.3, 0.4, 0.6],
    "flat_deg": [10.0, 15.0, 20.0],
    "seed_tolerance_m": [0.1, 0.2, 0.3],
    "base_band_m": [0.0, 0.05, 0.1, 0.15],
    # step 6, row neighbours (0 columns turns it off)
    "neighbour_px": [0, 3, 5, 10, 20, 40],
    "neighbour_band_m": [0.02, 0.03, 0.05, 0.08, 0.12],
    "foot_deg": [15.0, 20.0, 30.0, 45.0, 60.0],
    "under_m": [0.0, 0.5, 1.0, 2.0, 3.0, 5.0],
    "face_deg": [15.0, 20.0, 30.0, 45.0, 60.0, 90.0],
    # the pixels' geometry on projected scans, and step 7 (hidden points)
    "point_heights": [False, True],
    "hidden_points": [False, True],
    # step 8, the feet held out and attached
    "hold_feet": [False, True],
    "attach_m": [0.5, 1.0, 1.5, 2.5],
}


def load_frames(root: Path, cfg: dict, limit: int | None) -> list[tuple]:
    """(ground-setting frame, no-ground frame) pairs, prepared once."""
    ds = open_dataset(root)
    out = []
    for ref in ds.refs()[:limit]:
        frame = ds.load(ref)
        out.append((prepare(frame, "ground", cfg.projection),
                    prepare(frame, "no-ground", cfg.projection)))  # fmt: skip
    return out


def iou_mu(pairs: list[tuple], methods: dict, grounds: list[Ground] | None) -> dict[str, float]:
    """IoU_mu in % per method; ``grounds`` None = the no-ground setting."""
    ious: dict[str, list] = {m: [] for m in methods}
    for k, (g, n) in enumerate(pairs):
        prep = n if grounds is None else g
        for name, method in methods.items():
            if grounds is None:
                labels = method.segment(prep.image, prep.points, None)
            else:
                labels = cluster_ground(method, prep.points, grounds[k])
            ious[name].append(match_objects(prep.labels, labels).iou)
    return {f"iou_{m}": round(100 * float(np.mean(np.concatenate(v))), 2) for m, v in ious.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default="../shared/data/semantickitti", type=Path)
    parser.add_argument("--out", type=Path, default=Path("results/ground/sweep_column.csv"))
    parser.add_argument("--methods", default="flic0,flic6,flic14")
    parser.add_argument("--sample-frames", type=int, default=20, help="synthetic frames")
    parser.add_argument("--params", default=",".join(GRID), help="parameters to sweep")
    args = parser.parse_args()

    from flic_cli.sample import write_sample

    cfg = load_config()
    methods = {m: cfg.method(m).method for m in args.methods.split(",")}
    defaults = {f.name: f.default for f in fields(ColumnGround)}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        sample = write_sample(Path(tmp), frames=args.sample_frames)
        sets = {"semantickitti": args.data, "synthetic": sample.kitti_root}
        for set_name, root in sets.items():
            pairs = load_frames(root, cfg, None)
            reference = iou_mu(pairs, methods, None)
            swept = args.params.split(",")
            runs = [("default", None)] + [(p, v) for p in swept for v in GRID[p]
                                          if v != defaults[p]]  # fmt: skip
            for param, value in runs:
                remover = ColumnGround(**({} if param == "default" else {param: value}))
                grounds = [extract_ground(remover, g.image, g.points) for g, _ in pairs]
                counts = sum(
                    (ground_counts(g.labels, ground.on_ground) for (g, _), ground in
                     zip(pairs, grounds, strict=True)), GroundCounts()
                )  # fmt: skip
                scores = {k: round(v, 2) for k, v in ground_scores(counts).items()}
                row = {"data": set_name, "param": param,
                       "value": "" if value is None else value}  # fmt: skip
                row.update(scores)
                row.update(iou_mu(pairs, methods, grounds))
                for m in methods:
                    row[f"gap_{m}"] = round(reference[f"iou_{m}"] - row[f"iou_{m}"], 2)
                rows.append(row)
                print(row, flush=True)
    df = pd.DataFrame(rows)
    write_table(args.out, df)
    print(df.to_string(index=False))


if __name__ == "__main__":
    main()
