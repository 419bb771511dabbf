"""What per-point ground decisions would gain over per-pixel ones: the points hidden behind
their pixel's owner.

On a projected SemanticKITTI scan (2048 x 64, ring recovery) about 9 % of the points share a pixel
with a nearer point, the pixel's owner, and take the pixel's ground decision although they lie
behind it: ground seen just behind or under an object's lowest edge stays in the object's
pixel, and an object's point behind a road pixel is removed with it. This script measures, on
the ground setting with flic's ``column`` remover, the clusterers' IoU_mu gaps to the no-ground
setting when the hidden points get a decision of their own:

- ``pixel``: every point takes its pixel's decision (what flic does);
- ``labels on hidden points``: the hidden points take their ground-truth label (a bound: no
  remover knows it);
- ``row test on hidden points of object pixels``: a hidden point of a pixel that ``column`` did
  not take is ground when a pixel that ``column`` took in the same row, at most
  ``neighbour_px`` columns away, is within 1 m of its horizontal range and ``neighbour_band_m``
  of its height (``column``'s step 6 test, with its parameters); hidden points of ground pixels
  stay ground;
- ``row test on every hidden point``: the same test also decides the hidden points of ground
  pixels.

Point methods (DBSCAN) cluster the points not judged ground; image methods cluster the pixels as
flic does and then the hidden points judged ground lose their label (their pixel's cluster had
counted them towards its 100-point minimum: a version built into flic would count after).

Usage::

    python scripts/ground_hidden_points.py ../shared/data/semantickitti \\
        --out results/ground/hidden_points.csv
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from numba import njit

from flic_cli.classes import GROUND_LUT
from flic_cli.config import load_config
from flic_cli.ground.base import pixel_owners
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.methods.dbscan import Dbscan
from flic_cli.metrics import match_objects
from flic_cli.runs.pipeline import prepare

METHODS = "flic0,flic1,flic6,flic14,flic1n,flic6n,flic14n,bridge,dbscan-fast"
_ROW_DRHO_M = 1.0  # as column's step 6


@njit(cache=True)
def row_test(
    ranges: np.ndarray,
    elevation: np.ndarray,
    taken: np.ndarray,
    pixel: np.ndarray,
    rho: np.ndarray,
    z: np.ndarray,
    decide: np.ndarray,
    ground: np.ndarray,
    reach: int,
    band: float,
) -> np.ndarray:
    """``ground`` with the points of ``decide`` set by the row test (module docstring)."""
    h, w = ranges.shape
    out = ground.copy()
    for i in range(pixel.size):
        if not decide[i]:
            continue
        r = pixel[i] // w
        c = pixel[i] % w
        ce = np.cos(elevation[r])
        se = np.sin(elevation[r])
        hit = False
        for cc in range(max(c - reach, 0), min(c + reach + 1, w)):
            if taken[r, cc]:
                d = ranges[r, cc]
                if abs(d * ce - rho[i]) <= _ROW_DRHO_M and abs(d * se - z[i]) <= band:
                    hit = True
                    break
        out[i] = hit
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("--methods", default=METHODS)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()

    cfg = load_config()
    methods = {m: cfg.method(m).method for m in args.methods.split(",")}
    column = cfg.remover("column")
    ds = open_dataset(args.data)
    frames = []
    for ref in ds.refs():
        frame = ds.load(ref)
        g = prepare(frame, "ground", cfg.projection)
        n = prepare(frame, "no-ground", cfg.projection)
        img = g.image
        owner = pixel_owners(img, g.points)
        hidden = np.ones(g.points.shape[0], dtype=bool)
        hidden[owner[owner >= 0]] = False
        taken = column(img)
        pixel_ground = taken.reshape(-1)[img.point_pixel]
        xyz = np.asarray(g.points[:, :3], dtype=np.float64)
        rho, z = np.hypot(xyz[:, 0], xyz[:, 1]), xyz[:, 2]
        el = np.asarray(img.elevation, dtype=np.float64)

        def test(decide, pixel_ground=pixel_ground, img=img, taken=taken, rho=rho, z=z, el=el):
            return row_test(img.ranges, el, taken, img.point_pixel, rho, z, decide,
                            pixel_ground, column.neighbour_px, column.neighbour_band_m)  # fmt: skip

        label_ground = GROUND_LUT[g.labels & 0xFFFF]
        variants = {
            "pixel": pixel_ground,
            "labels on hidden points": np.where(hidden, label_ground, pixel_ground),
            "row test on hidden points of object pixels": test(hidden & ~pixel_ground),
            "row test on every hidden point": test(hidden),
        }
        frames.append((g, n, taken, hidden, variants))
    print(f"hidden points: {np.mean(np.concatenate([f[3] for f in frames])):.1%} of all")

    def iou(method, variant: str | None) -> float:
        ious = []
        for g, n, taken, _, variants in frames:
            if variant is None:
                labels = method.segment(n.image, n.points, None)
                ious.append(match_objects(n.labels, labels).iou)
                continue
            on_ground = variants[variant]
            if isinstance(method, Dbscan):
                from flic_cli.methods.dbscan import dbscan_labels

                labels = np.zeros(g.points.shape[0], dtype=np.int32)
                keep = ~on_ground
                labels[keep] = dbscan_labels(g.points[keep], method.eps_m, method.min_samples,
                                             method.min_size, method.backend)  # fmt: skip
            else:
                labels = np.where(on_ground, 0, method.segment(g.image, g.points, taken))
            ious.append(match_objects(g.labels, labels).iou)
        return 100 * float(np.mean(np.concatenate(ious)))

    rows = []
    reference = {m: iou(method, None) for m, method in methods.items()}
    for variant in frames[0][4]:
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
