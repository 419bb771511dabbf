"""Agreement of flic's Bogoslavskyi ground remover with their C++ (PRBonn/depth_clustering).

Their ``DepthGroundRemover`` is built and run outside this project (its code is not part of
flic); for every PNG of a Moosmann-style log, in sorted order, it wrote the ground mask it
computed as ``NNNNN.ground``: H x W bytes, row-major, 1 = ground (a pixel that their repaired
depth image holds and their no-ground image zeroes). This script runs
:func:`flic_cli.ground.bogoslavskyi_ground` on the same log and compares, over the pixels that hold
a measurement in the log: the share of pixels on which the two masks agree and the ground share
of each. Writes one row per frame and prints the pooled figures.

Usage::

    python scripts/bogoslavskyi_fidelity.py LOG MASKS --out results/ground/bogoslavskyi_fidelity.csv
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", type=Path, help="Moosmann-style log (img.cfg + PNGs)")
    parser.add_argument("masks", type=Path, help="folder of their NNNNN.ground files")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()

    cfg = load_config()
    remover = cfg.remover("bogoslavskyi")
    ds = open_dataset(args.log)
    rows = []
    for i, ref in enumerate(ds.refs()):
        image = ds.load(ref).image
        theirs = np.fromfile(args.masks / f"{i:05d}.ground", dtype=np.uint8)
        theirs = theirs.reshape(image.ranges.shape).astype(bool)
        ours = remover.extract(image, None).mask
        valid = image.ranges > 0
        rows.append(
            {
                "frame": ref.frame,
                "valid": int(valid.sum()),
                "differ": int((theirs[valid] != ours[valid]).sum()),
                "ground_cpp": int(theirs[valid].sum()),
                "ground_flic": int(ours[valid].sum()),
            }
        )
    df = pd.DataFrame(rows)
    n = df["valid"].sum()
    print(
        f"{len(df)} frames, {n} valid pixels: agreement {1 - df['differ'].sum() / n:.6f} "
        f"(per frame min {(1 - df['differ'] / df['valid']).min():.6f}); ground share "
        f"C++ {df['ground_cpp'].sum() / n:.4f}, flic {df['ground_flic'].sum() / n:.4f}"
    )
    if args.out is not None:
        write_table(args.out, df)


if __name__ == "__main__":
    main()
