"""How close a per-pixel ground remover can get: the clusterers' IoU_mu gaps with masks taken
from the labels, and with the labels' decision withheld where geometry cannot know it.

Every pixel (at its nearest point's height, as ``column`` sees it) gets a category from the next
valid cell above it (within 3 rows): ``under`` (that
cell is nearer by more than 0.3 m: an occluder), ``foot`` (it rises from the pixel more steeply
than 30 deg), else ``free`` (farther, flat, or nothing above); ``-thing`` when the point owning
that cell is a thing object's (a label, which a remover does not have). Masks:

- ``labels, per point``: every point of a ground class is ground, whatever its pixel (the points
  taken outside ground pixels leave their pixel, as step 7's do: a perfect per-point remover);
- ``labels``: a pixel is ground when the point that owns it (the nearest) is of a ground class;
- ``labels - thing feet``: the same, but ground pixels under or at the foot of a thing object
  left (what a remover that keeps every object's foot does);
- ``labels - other feet``: ground pixels at the foot of anything else left;
- ``column``: flic's remover as ``flic evaluate`` runs it (steps 1-8: hidden points decided one
  by one, the feet held out and attached); ``column + labels at thing feet``: the remover's
  pixel mask (steps 1-6), with the labels' decision on the pixels under or at the foot of thing
  objects.

Writes one row per mask: ground precision / recall / F1, thing points removed, IoU_mu per method
and the gap to the no-ground setting. With ``--counts`` it also prints, for the pixels the remover
leaves within ``--band`` of the ground taken in the same row (+-10 columns, same range within 1 m),
how many are labelled ground, thing or other, per category: the split that no geometric rule sees.

Usage::

    python scripts/ground_oracle.py ../shared/data/semantickitti \\
        --methods flic0,flic6,flic14,bridge,dbscan-fast --out results/ground/oracle.csv --counts
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from numba import njit

from flic_cli.classes import GROUND_LUT, THING_LUT
from flic_cli.config import load_config
from flic_cli.ground.base import Ground, extract_ground, leave_pixels, pixel_owners
from flic_cli.ground.column import pixel_geometry
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.metrics import match_objects
from flic_cli.metrics.ground import GroundCounts, ground_counts, ground_scores
from flic_cli.runs.pipeline import cluster_ground, prepare

CATEGORIES = ("free", "under", "foot", "free-thing", "under-thing", "foot-thing")


@njit(cache=True)
def categories(rho: np.ndarray, z: np.ndarray, thing: np.ndarray) -> np.ndarray:
    """(H, W) int8 index into :data:`CATEGORIES` (-1 where empty)."""
    h, w = rho.shape
    out = np.full((h, w), -1, dtype=np.int8)
    tan30 = np.tan(np.radians(30.0))
    for r in range(h):
        for c in range(w):
            if rho[r, c] <= 0.0:
                continue
            k = 0
            for ra in range(r - 1, max(r - 4, -1), -1):
                if rho[ra, c] <= 0.0:
                    continue
                d = rho[ra, c] - rho[r, c]
                if d < -0.3:
                    k = 1
                elif z[ra, c] - z[r, c] > tan30 * abs(d):
                    k = 2
                if thing[ra, c]:
                    k += 3
                break
            out[r, c] = k
    return out


@njit(cache=True)
def row_height(rho: np.ndarray, z: np.ndarray, taken: np.ndarray) -> np.ndarray:
    """Height of every pixel above the mean of the taken pixels of its row within 10 columns
    and 1 m of range (NaN where there are none)."""
    h, w = rho.shape
    out = np.full((h, w), np.nan)
    for r in range(h):
        for c in range(w):
            if rho[r, c] <= 0.0:
                continue
            s = 0.0
            n = 0
            for q in range(max(c - 10, 0), min(c + 11, w)):
                if taken[r, q] and abs(rho[r, q] - rho[r, c]) < 1.0:
                    s += z[r, q]
                    n += 1
            if n:
                out[r, c] = z[r, c] - s / n
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("--methods", default="flic0,flic6,flic14,bridge,dbscan-fast")
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--counts", action="store_true")
    parser.add_argument("--band", type=float, default=0.05, help="metres, for --counts")
    args = parser.parse_args()

    cfg = load_config()
    methods = {m: cfg.method(m).method for m in args.methods.split(",")}
    column = cfg.remover("column")
    ds = open_dataset(args.data)
    grounds: dict[str, list[Ground]] = {k: [] for k in (
        "labels, per point", "labels", "labels - thing feet", "labels - other feet", "column",
        "column + labels at thing feet")}  # fmt: skip
    pairs = []
    counts = np.zeros((len(CATEGORIES), 3), dtype=np.int64)
    for ref in ds.refs():
        frame = ds.load(ref)
        g = prepare(frame, "ground", cfg.projection)
        n = prepare(frame, "no-ground", cfg.projection)
        pairs.append((g, n))
        img = g.image
        owner = pixel_owners(img, g.points).reshape(img.ranges.shape)
        lab = np.where(owner >= 0, g.labels[np.maximum(owner, 0)], 0)
        sem = lab & 0xFFFF
        thing = THING_LUT[sem] & ((lab >> 16) > 0) & (owner >= 0)
        gr = GROUND_LUT[sem] & (owner >= 0)
        rho, z = pixel_geometry(img)[:2]
        cat = categories(rho, z, thing)
        thing_feet = (cat == 4) | (cat == 5)
        other_feet = (cat == 1) | (cat == 2)
        col = column.extract(img, g.points).mask
        on_ground = GROUND_LUT[g.labels & 0xFFFF]
        grounds["labels, per point"].append(Ground(gr, leave_pixels(img, gr, on_ground), on_ground))
        for name, mask in (
            ("labels", gr),
            ("labels - thing feet", gr & ~thing_feet),
            ("labels - other feet", gr & ~other_feet),
            ("column + labels at thing feet", np.where(thing_feet, gr, col)),
        ):
            grounds[name].append(Ground(mask, img))
        grounds["column"].append(extract_ground(column, img, g.points))
        if args.counts:
            hh = row_height(rho, z, col)
            near = (img.ranges > 0) & ~col & (np.abs(np.nan_to_num(hh, nan=9.0)) <= args.band)
            for k in range(len(CATEGORIES)):
                s = near & (cat == k)
                counts[k] += [(s & gr).sum(), (s & thing).sum(), (s & ~gr & ~thing).sum()]

    def iou(use: list[Ground] | None) -> dict[str, float]:
        res = {}
        for name, method in methods.items():
            ious = []
            for k, (g, n) in enumerate(pairs):
                if use is None:
                    labels = method.segment(n.image, n.points, None)
                    ious.append(match_objects(n.labels, labels).iou)
                else:
                    labels = cluster_ground(method, g.points, use[k])
                    ious.append(match_objects(g.labels, labels).iou)
            res[name] = 100 * float(np.mean(np.concatenate(ious)))
        return res

    reference = iou(None)
    rows = []
    for name, gs in grounds.items():
        c = sum((ground_counts(g.labels, ground.on_ground) for (g, _), ground in
                 zip(pairs, gs, strict=True)), GroundCounts())  # fmt: skip
        row = {"mask": name, **{k: round(v, 2) for k, v in ground_scores(c).items()}}
        got = iou(gs)
        for m in methods:
            row[f"iou_{m}"] = round(got[m], 2)
            row[f"gap_{m}"] = round(reference[m] - got[m], 2)
        rows.append(row)
    df = pd.DataFrame(rows)
    print(df.to_string(index=False))
    if args.out is not None:
        write_table(args.out, df)
    if args.counts:
        print(f"\npixels the remover leaves within {args.band} m of the row's taken ground:")
        cdf = pd.DataFrame(counts, index=CATEGORIES, columns=["ground", "thing", "other"])
        print(cdf.to_string())
        if args.out is not None:
            counts_out = args.out.with_name(args.out.stem + "_counts.csv")
            write_table(counts_out, cdf.rename_axis("category").reset_index())


if __name__ == "__main__":
    main()
