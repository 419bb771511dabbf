"""What per-point ground decisions gain over per-pixel ones: the points hidden behind their
pixel's nearest point, and ``column``'s step 7.

On a projected SemanticKITTI scan (2048 x 64, ring recovery) about 9 % of the points share a pixel
with a nearer point and lie behind it. With per-pixel decisions they take their pixel's: ground
seen just behind or under an object's lowest edge stays with the object's pixel, and an
object's point behind a road pixel is removed with it. This script measures, in the ground
setting with flic's ``column`` remover, the clusterers' IoU_mu gaps to the no-ground setting when
the hidden points (those that are not the nearest of their pixel) are decided:

- ``pixel``: by their pixel (``column`` without step 7, ``hidden_points = false``);
- ``labels on hidden points``: by their ground-truth label (a bound: no remover knows it);
- ``step 7``: by ``column``'s step 7 (its default).

Every variant is a :class:`flic_cli.ground.base.Ground`, as ``flic evaluate`` makes it
(``extract_ground``; the labels' variant from its decision with ``leave_pixels``): the points
taken as ground outside ground pixels leave their pixel, so every clusterer leaves them out.
``column`` runs without step 8 (``hold_feet = false``), so that only the hidden points'
decision differs between the variants.

Usage::

    python scripts/ground_hidden_points.py ../shared/data/semantickitti \\
        --out results/ground/hidden_points.csv
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.classes import GROUND_LUT
from flic_cli.config import load_config
from flic_cli.ground import ColumnGround
from flic_cli.ground.base import (
    Ground,
    extract_ground,
    leave_pixels,
    pixel_owners,
    point_ground,
)
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.metrics import match_objects
from flic_cli.runs.pipeline import prepare

METHODS = "flic0,flic1,flic6,flic14,flic1n,flic6n,flic14n,bridge,dbscan-fast"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("--methods", default=METHODS)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()

    cfg = load_config()
    methods = {m: cfg.method(m).method for m in args.methods.split(",")}
    # steps 1-7 only: step 8's held feet would change the clustering of every variant but the
    # labels' (which has none), and this compares the hidden points' decision alone
    column = ColumnGround(**{**cfg.remover("column").__dict__, "hold_feet": False})
    pixel_only = ColumnGround(**{**column.__dict__, "hidden_points": False})
    ds = open_dataset(args.data)
    frames = []
    hidden_share = []
    for ref in ds.refs():
        frame = ds.load(ref)
        g = prepare(frame, "ground", cfg.projection)
        n = prepare(frame, "no-ground", cfg.projection)
        img = g.image
        owner = pixel_owners(img, g.points)
        hidden = np.ones(g.points.shape[0], dtype=bool)
        hidden[owner[owner >= 0]] = False
        hidden_share.append(hidden)
        mask = column.extract(img, g.points).mask
        labels = np.where(hidden, GROUND_LUT[g.labels & 0xFFFF], point_ground(img, mask))
        variants: dict[str, Ground] = {
            "pixel": extract_ground(pixel_only, img, g.points),
            "labels on hidden points": Ground(mask, leave_pixels(img, mask, labels), labels),
            "step 7": extract_ground(column, img, g.points),
        }
        frames.append((g, n, variants))
    print(f"hidden points: {np.mean(np.concatenate(hidden_share)):.1%} of all")

    def iou(method, variant: str | None) -> float:
        ious = []
        for g, n, variants in frames:
            if variant is None:
                labels = method.segment(n.image, n.points, None)
                ious.append(match_objects(n.labels, labels).iou)
            else:
                ground = variants[variant]
                labels = method.segment(ground.image, g.points, ground.mask)
                ious.append(match_objects(g.labels, labels).iou)
        return 100 * float(np.mean(np.concatenate(ious)))

    rows = []
    reference = {m: iou(method, None) for m, method in methods.items()}
    for variant in frames[0][2]:
        row = {"hidden points": variant}
        for m, method in methods.items():
            got = iou(method, variant)
            row[f"iou_{m}"] = round(got, 2)
            row[f"gap_{m}"] = round(reference[m] - got, 2)
        rows.append(row)
    df = pd.DataFrame(rows)
    print(df.to_string(index=False))
    if args.out is not None:
        write_table(args.out, df)


if __name__ == "__main__":
    main()
