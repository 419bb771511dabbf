"""What the ground extraction does to the GT objects (why the "ground" column is lower).

For each ground remover, over every frame: the share of GT thing-object points (objects with >= 100
points) that it marks as ground, where on the objects those points are (relative height, 0 = the
object's lowest point, 1 = its top), how far away those objects are, the share of the GT ground
classes it removes, and for FLIC 0 MC on what is left the recall (overlap / object) and precision
(overlap / cluster) of each object's matched cluster. Writes ``results/ground_diagnostics.csv``.

Usage: python scripts/ground_diagnostics.py [DATA] [--removers paper,bogoslavskyi,column]
       [--out results/ground/diagnostics.csv]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from flic_cli.classes import GROUND_CLASSES, THING_CLASSES
from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.metrics import match_objects
from flic_cli.runs.pipeline import build_segmenter, prepare


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default="../shared/data/semantickitti", type=Path)
    parser.add_argument("--removers", default="paper,bogoslavskyi,column")
    parser.add_argument("--out", type=Path, default=Path("results/ground/diagnostics.csv"))
    args = parser.parse_args()
    cfg = load_config()
    ds = open_dataset(args.data)
    rows = []
    for remover in args.removers.split(","):
        seg = build_segmenter(cfg, "flic0", "ground", remover)
        removed_rel, removed_dist, recall, precision = [], [], [], []
        obj_pts = obj_removed = gnd_pts = gnd_removed = 0
        for ref in tqdm(ds.refs(), desc=remover, unit="frame"):
            prep = prepare(ds.load(ref), "ground", cfg.projection)
            labels, ground = seg.run(prep.image, prep.points)
            on_ground = ground.on_ground
            sem = prep.labels & 0xFFFF
            is_gnd = np.isin(sem, GROUND_CLASSES)
            gnd_pts += int(is_gnd.sum())
            gnd_removed += int((on_ground & is_gnd).sum())
            things = np.isin(sem, THING_CLASSES) & (prep.labels >> 16 > 0)
            for obj in np.unique(prep.labels[things]):
                pts = prep.labels == obj
                if pts.sum() < 100:
                    continue
                z = prep.points[pts, 2]
                rel = (z - z.min()) / max(float(z.max() - z.min()), 1e-6)
                gone = on_ground[pts]
                obj_pts += int(pts.sum())
                obj_removed += int(gone.sum())
                removed_rel.append(rel[gone])
                dist = float(np.linalg.norm(prep.points[pts].mean(axis=0)))
                removed_dist.append(np.full(int(gone.sum()), dist))
            m = match_objects(prep.labels, labels)
            sizes = np.bincount(labels)
            for n, c, o in zip(m.n_points, m.cluster, m.overlap, strict=True):
                recall.append(o / n if c > 0 else 0.0)
                precision.append(o / sizes[c] if c > 0 else np.nan)
        rel = np.concatenate(removed_rel)
        dist = np.concatenate(removed_dist)
        hist = np.histogram(rel, bins=5, range=(0, 1))[0] / max(rel.size, 1)
        rows.append(
            dict(
                remover=remover,
                object_points_removed=round(obj_removed / obj_pts, 4),
                ground_class_points_removed=round(gnd_removed / gnd_pts, 4),
                **{f"removed_in_height_fifth_{i + 1}": round(h, 3) for i, h in enumerate(hist)},
                removed_object_distance_p10_m=round(float(np.percentile(dist, 10)), 1),
                removed_object_distance_p90_m=round(float(np.percentile(dist, 90)), 1),
                flic0_recall_median=round(float(np.median(recall)), 3),
                flic0_precision_median=round(float(np.nanmedian(precision)), 3),
            )
        )
    df = pd.DataFrame(rows)
    write_table(args.out, df)
    print(df.T.to_string(header=False))


if __name__ == "__main__":
    main()
