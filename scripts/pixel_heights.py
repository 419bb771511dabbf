"""How far a projected pixel's height along its row's elevation is from its nearest point's.

A projected range image gives every row one elevation (rings: the median of the beam's points;
spherical: the middle of the bin). A pixel's height "along its row" is ``range * sin(elevation)``;
its true height is that of its nearest point (``RangeImage.point_z``); both as ``column`` sees
them (:func:`flic_cli.ground.column.pixel_geometry`). For every pixel of the
ground setting's image (all points projected) this prints, over all frames, the percentiles of
the difference (true minus row height) and the shares beyond 3 and 8 cm (the ``column``
remover's bands are 3-8 cm), for all valid pixels and for those whose nearest point has a
ground class; the horizontal range likewise. Writes one row per pixel set to ``--out``.

Usage::

    python scripts/pixel_heights.py ../shared/data/semantickitti \\
        --out results/ground/pixel_heights.csv
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from flic_cli.classes import ground_mask
from flic_cli.config import load_config
from flic_cli.ground.base import pixel_owners
from flic_cli.ground.column import pixel_geometry
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.runs.pipeline import prepare


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default="../shared/data/semantickitti", type=Path)
    parser.add_argument("--out", type=Path, default=Path("results/ground/pixel_heights.csv"))
    args = parser.parse_args()
    cfg = load_config()
    ds = open_dataset(args.data)
    dz: dict[str, list] = {"all valid pixels": [], "ground-class pixels": []}
    drho: dict[str, list] = {k: [] for k in dz}
    for ref in tqdm(ds.refs(), unit="frame"):
        prep = prepare(ds.load(ref), "ground", cfg.projection)
        image = prep.image
        valid = image.ranges.reshape(-1) > 0
        true_rho, true_z = (a.reshape(-1) for a in pixel_geometry(image, exact=True)[:2])
        row_rho, row_z = (a.reshape(-1) for a in pixel_geometry(image, exact=False)[:2])
        owner = pixel_owners(image, prep.points)
        on_ground = np.zeros_like(valid)
        on_ground[valid] = ground_mask(prep.labels)[owner[valid]]
        for name, sel in (("all valid pixels", valid), ("ground-class pixels", on_ground)):
            dz[name].append(true_z[sel] - row_z[sel])
            drho[name].append(true_rho[sel] - row_rho[sel])
    rows = []
    for name in dz:
        z = np.concatenate(dz[name])
        r = np.concatenate(drho[name])
        p1, p10, p50, p90, p99 = np.percentile(z, [1, 10, 50, 90, 99])
        rows.append(
            {
                "pixels": name,
                "count": z.size,
                "dz_p1_cm": round(100 * p1, 1),
                "dz_p10_cm": round(100 * p10, 1),
                "dz_median_cm": round(100 * p50, 1),
                "dz_p90_cm": round(100 * p90, 1),
                "dz_p99_cm": round(100 * p99, 1),
                "share_dz_over_3cm": round(float(np.mean(np.abs(z) > 0.03)), 3),
                "share_dz_over_8cm": round(float(np.mean(np.abs(z) > 0.08)), 3),
                "drho_p1_cm": round(100 * float(np.percentile(r, 1)), 1),
                "drho_p99_cm": round(100 * float(np.percentile(r, 99)), 1),
            }
        )
    table = pd.DataFrame(rows)
    write_table(args.out, table)
    print(table.to_string(index=False))


if __name__ == "__main__":
    main()
