"""The column ground remover per sensor profile, before and after its run limits followed the
beam table (issue 21: column's thresholds).

For every sensor profile (``flic sample --sensor``, the street of seed 0) and every frame, the
ground setting's image and points, and column's decision twice: ``before``, the fixed depth-jump
limit of its confirming runs (``run_jump = 0.3`` on every row, what flic did before), and
``after``, the per-row limits from the beam table
(:func:`flic_cli.sensor_params.column_run_jumps`, the default now). Scored as ``flic evaluate``
scores a remover (:func:`flic_cli.metrics.ground.ground_counts`: points of the ground classes,
pooled over the frames): precision, recall, F1, and the share of thing-object points taken.
Also the ground recall of the bottom two rows, where the VLP-32C's beams are farthest apart.

Usage (from the repository root; ``../shared`` not needed)::

    python scripts/sensors_ground_column.py --frames 20 --work /tmp/flic-ground-column \\
        --out results/sensors-synthetic/ground-column/before_after.csv
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.classes import ground_mask
from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.metrics.ground import GroundCounts, ground_counts
from flic_cli.runs.pipeline import prepare
from flic_cli.sample import SENSOR_PROFILES, write_sample
from flic_cli.sensor_params import RUN_JUMP_FLOOR


def sensor_rows(name: str, frames: int, work: Path) -> list[dict]:
    """Column's scores on one sensor's street, before and after."""
    folder = work / name
    if not (folder / "semantickitti").is_dir():
        write_sample(folder, frames=frames, seed=0, sensor=name)
    paths_config = folder / "sensor.toml"
    config = load_config(paths_config if paths_config.is_file() else None)
    after = config.remover("column")
    variants = {"before": dataclasses.replace(after, run_jump=RUN_JUMP_FLOOR), "after": after}
    ds = open_dataset(folder / "semantickitti", None, (0, frames))
    refs = ds.refs()[:frames]
    counts = {k: GroundCounts() for k in variants}
    bottom = {k: [0, 0] for k in variants}
    changed_rows = 0
    for ref in refs:
        prep = prepare(ds.load(ref), "ground", config.projection)
        w = prep.image.shape[1]
        rows = np.where(prep.image.point_pixel >= 0, prep.image.point_pixel // w, -1)
        low = rows >= prep.image.shape[0] - 2
        changed_rows = int(np.count_nonzero(after.run_jumps(prep.image) != RUN_JUMP_FLOOR))
        truth = ground_mask(prep.labels)
        for key, remover in variants.items():
            taken = remover.extract(prep.image, prep.points).on_ground
            counts[key] = counts[key] + ground_counts(prep.labels, taken)
            bottom[key][0] += int(np.count_nonzero(taken & truth & low))
            bottom[key][1] += int(np.count_nonzero(truth & low))
    out = []
    for key in variants:
        c = counts[key]
        out.append(
            {
                "sensor": name,
                "beams": SENSOR_PROFILES[name].beams,
                "columns": SENSOR_PROFILES[name].width,
                "column": key,
                "frames": len(refs),
                "rows_with_derived_limit": changed_rows,
                "precision": round(100 * c.precision, 2),
                "recall": round(100 * c.recall, 2),
                "f1": round(100 * c.f1, 2),
                "thing_points_removed": round(100 * c.things_removed_share, 2),
                "bottom_two_rows_recall": round(100 * bottom[key][0] / max(bottom[key][1], 1), 2),
            }
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--work", type=Path, default=Path("/tmp/flic-ground-column"))
    ap.add_argument("--sensors", default=",".join(SENSOR_PROFILES))
    ap.add_argument(
        "--out", type=Path, default=Path("results/sensors-synthetic/ground-column/before_after.csv")
    )
    args = ap.parse_args()
    rows = []
    for name in args.sensors.split(","):
        rows += sensor_rows(name, args.frames, args.work)
        print(pd.DataFrame(rows[-2:]).to_string(index=False), flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_table(args.out, pd.DataFrame(rows))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
