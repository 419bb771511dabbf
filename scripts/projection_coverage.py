"""Projection coverage of the ring recovery vs the spherical projection on SemanticKITTI frames.

Coverage = share of a scan's points that own a pixel of the 64 x WIDTH range image (the others
share a pixel with a nearer point). Also counts the rows a naive rule finds (a new row at every
+-180 deg azimuth jump). Writes ``results/projection_coverage.csv`` and prints the means.

Usage: python scripts/projection_coverage.py [DATA] [--width 2048] [--out CSV]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.projection import project_points


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default="../shared/data/semantickitti", type=Path)
    parser.add_argument("--width", type=int, default=2048)
    parser.add_argument("--out", type=Path, default=Path("results/projection_coverage.csv"))
    args = parser.parse_args()
    ds = open_dataset(args.data)
    rows = []
    for ref in tqdm(ds.refs(), unit="frame"):
        pts = ds.load(ref).points
        rings = project_points(pts, width=args.width)
        sph = project_points(pts, width=args.width, mode="spherical")
        rows.append(
            dict(
                sequence=ref.sequence,
                frame=ref.frame,
                points=len(pts),
                rows_recovered=rings.shape[0] if rings.projection == "rings" else 0,
                rows_naive=int((np.diff(np.arctan2(pts[:, 1], pts[:, 0])) < -np.pi).sum()) + 1,
                coverage_rings=round(rings.coverage, 5),
                coverage_spherical=round(sph.coverage, 5),
            )
        )
    df = pd.DataFrame(rows)
    write_table(args.out, df)
    print(
        f"{len(df)} frames, width {args.width}: "
        f"mean coverage rings {100 * df.coverage_rings.mean():.2f}% "
        f"(min {100 * df.coverage_rings.min():.2f}%), "
        f"spherical {100 * df.coverage_spherical.mean():.2f}% "
        f"(min {100 * df.coverage_spherical.min():.2f}%); rows: recovered "
        f"{df.rows_recovered.min()}-{df.rows_recovered.max()}, naive rule "
        f"{df.rows_naive.min()}-{df.rows_naive.max()} -> {args.out}"
    )


if __name__ == "__main__":
    main()
