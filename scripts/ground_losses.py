"""Where a clusterer loses IoU in the ground setting: ground left in its clusters, object points
taken as ground, and objects merged through a few leftover ground points.

**Per object** (``OUT_objects.csv``): for every ground-truth object (thing classes, >= 100
points) in the ground setting with the remover, its points, those of its points on pixels the
remover took as ground (``removed``), the cluster holding most of its points (``cluster``
points, ``overlap`` with the object), the ground-class points in that cluster
(``ground_in_cluster``), the IoU of object and cluster and the IoU the same cluster would have
without its ground-class points (``iou_without_ground``). This IoU is the object's IoU with its
majority cluster, a simpler matching than the protocol's one-cluster-one-object rule
(docs/specification.md), so its mean differs from ``flic evaluate``'s IoU_mu by a few tenths.

**Merged pairs** (``OUT_pairs.csv``): for every frame, the method runs in the no-ground setting
(ground removed by label) and in the ground setting with the remover. A pair of ground-truth
objects is *merged only with the remover* when the cluster holding most of each object's points
is the same cluster in the ground setting but not in the no-ground setting. For each such
cluster the script counts the points of ground classes that the remover left in it and runs the
method again with just those points' pixels marked as ground: if the pair then separates, those
few leftover ground points were the stepping stones that linked the two objects.

Usage::

    python scripts/ground_losses.py ../shared/data/semantickitti --method bridge \\
        --remover column --out results/ground/losses_bridge
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from flic_cli.classes import ground_mask, thing_mask
from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.runs.pipeline import build_segmenter, prepare

MIN_POINTS = 100


def majority_clusters(labels: np.ndarray, gt: np.ndarray) -> dict[int, int]:
    """Each thing object (full label, >= MIN_POINTS points) -> its majority cluster (0 = none)."""
    out = {}
    things = thing_mask(gt)
    ids, counts = np.unique(gt[things], return_counts=True)
    for obj in ids[counts >= MIN_POINTS]:
        out[int(obj)] = int(np.bincount(labels[gt == obj]).argmax())
    return out


def merged_pairs(clusters: dict[int, int]) -> set[tuple[int, int]]:
    """Pairs of objects whose majority cluster is the same non-zero cluster."""
    by_cluster: dict[int, list[int]] = {}
    for obj, c in clusters.items():
        if c > 0:
            by_cluster.setdefault(c, []).append(obj)
    return {(a, b) for objs in by_cluster.values() for a in objs for b in objs if a < b}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("--method", default="bridge")
    parser.add_argument("--remover", default="column")
    parser.add_argument("--out", type=Path, required=True, help="prefix of the two CSV files")
    args = parser.parse_args()
    cfg = load_config()
    ds = open_dataset(args.data)
    seg_ng = build_segmenter(cfg, args.method, "no-ground")
    seg_g = build_segmenter(cfg, args.method, "ground", args.remover)
    rows = []
    objects = []
    for ref in tqdm(ds.refs(), unit="frame"):
        frame = ds.load(ref)
        prep = prepare(frame, "no-ground", cfg.projection)
        alone = merged_pairs(majority_clusters(seg_ng(prep.image, prep.points)[0], prep.labels))
        prep = prepare(frame, "ground", cfg.projection)
        labels, ground = seg_g.run(prep.image, prep.points)
        clusters = majority_clusters(labels, prep.labels)
        on_ground = ground.on_ground
        ground_class = ground_mask(prep.labels)
        for obj, c in clusters.items():
            points = prep.labels == obj
            cluster = labels == c if c > 0 else np.zeros_like(points)
            n, size = int(points.sum()), int(cluster.sum())
            overlap = int((cluster & points).sum())
            left = int((cluster & ground_class).sum())
            objects.append(
                {
                    "sequence": ref.sequence,
                    "frame": ref.frame,
                    "object": obj,
                    "class": obj & 0xFFFF,
                    "points": n,
                    "removed": int((points & on_ground).sum()),
                    "cluster": size,
                    "overlap": overlap,
                    "ground_in_cluster": left,
                    "iou": overlap / (n + size - overlap),
                    "iou_without_ground": overlap / (n + size - left - overlap),
                }
            )
        for a, b in sorted(merged_pairs(clusters) - alone):
            cluster = labels == clusters[a]
            stones = cluster & ground_mask(prep.labels) & (ground.image.point_pixel >= 0)
            mask = ground.mask.copy().reshape(-1)
            mask[ground.image.point_pixel[stones]] = True
            again = seg_g.cluster(
                prep.image,
                prep.points,
                dataclasses.replace(ground, mask=mask.reshape(ground.mask.shape)),
            )
            after = majority_clusters(again, prep.labels)
            rng = np.linalg.norm(prep.points[cluster, :3], axis=1)
            rows.append(
                {
                    "sequence": ref.sequence,
                    "frame": ref.frame,
                    "object_a": a,
                    "object_b": b,
                    "class_a": a & 0xFFFF,
                    "class_b": b & 0xFFFF,
                    "cluster_points": int(cluster.sum()),
                    "median_range_m": round(float(np.median(rng)), 1),
                    "ground_points_left": int(stones.sum()),
                    "separate_without_them": after[a] != after[b] or after[a] == 0,
                }
            )
    objs = pd.DataFrame(objects)
    write_table(f"{args.out}_objects.csv", objs)
    print(
        f"{args.method} with the {args.remover} remover: IoU with the majority cluster "
        f"{100 * objs.iou.mean():.2f}, {100 * objs.iou_without_ground.mean():.2f} without the "
        f"ground-class points in the clusters ({int(objs.ground_in_cluster.sum())} points in the "
        f"clusters of {int((objs.ground_in_cluster > 0).sum())} of {len(objs)} objects); "
        f"{int(objs.removed.sum())} object points of {int((objs.removed > 0).sum())} objects "
        "taken as ground"
    )
    table = pd.DataFrame(rows)
    write_table(f"{args.out}_pairs.csv", table)
    n = len(table)
    if n:
        sep = int(table.separate_without_them.sum())
        print(
            f"{n} object pairs merged only with the {args.remover} remover; {sep} separate when "
            f"the ground points left in their cluster (median {table.ground_points_left.median():g}"
            f", range {table.ground_points_left.min()}-{table.ground_points_left.max()}) are "
            f"removed; median range {table.median_range_m.median():g} m -> {args.out}_pairs.csv"
        )
    else:
        print(f"no object pair merged only with the {args.remover} remover -> {args.out}_pairs.csv")


if __name__ == "__main__":
    main()
