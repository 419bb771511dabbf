"""Write SemanticKITTI scans as an 870 x 64 Moosmann-style log (16-bit PNG ranges + img.cfg).

The synthetic log of ``flic sample`` is a cheap case for timing: its ego car hides most of the
road, so the ground removers and the growth of Bogoslavskyi's remover see little ground (about
5 % of the pixels, where a real HDL-64E log has about half). KITTI's scans come from the same
sensor model as the Karlsruhe logs (Velodyne HDL-64E, 1.73 m above the road), so the same scans
binned to 870 columns are a log with real ground, vegetation and clutter, for timing on content
like the real logs (the real logs' licence forbids shipping them, docs/specification.md).

Every scan is projected with flic's ring recovery at 870 columns (column 0 = yaw +180 deg, the
Moosmann convention), the nearest point per pixel; the rows' pitch is the negated median
elevation of each ring. Scan ``NNNNN`` = sequence * 1000 + frame.

Usage: python scripts/kitti_as_moosmann.py ../shared/data/semantickitti /tmp/kitti-log
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from tqdm import tqdm

from flic_cli.io import open_dataset
from flic_cli.io.moosmann import ImgCfg, write_img_cfg, write_png_range
from flic_cli.io.semantickitti import read_bin
from flic_cli.projection import project_points

WIDTH = 870


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path, help="SemanticKITTI root (sequences/NN/velodyne)")
    parser.add_argument("out", type=Path, help="log folder to write")
    args = parser.parse_args()
    ds = open_dataset(args.data)
    args.out.mkdir(parents=True, exist_ok=True)
    pitches = []
    for ref in tqdm(ds.refs(), unit="scan"):
        image = project_points(read_bin(ref.path)[:, :3], width=WIDTH)
        if image.projection != "rings":
            raise SystemExit(f"{ref.path}: ring recovery failed, not a scan in sensor order")
        number = int(ref.sequence) * 1000 + ref.frame
        write_png_range(args.out / f"scan{number:05d}.png", image.ranges)
        pitches.append(-np.degrees(image.elevation))
    pitch = np.median(np.stack(pitches), axis=0)
    write_img_cfg(
        args.out / "img.cfg",
        ImgCfg(WIDTH, pitch.size, 180, -180, pitch),
        comment=f"SemanticKITTI scans of {args.data} binned to {WIDTH} columns",
        pitch_format=".4f",
    )
    print(f"{len(pitches)} scans written to {args.out}")


if __name__ == "__main__":
    main()
