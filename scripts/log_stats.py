"""Per-frame pixel and cluster counts of a range-image log (how alike two logs are for timing).

For every frame: valid pixels, pixels left after the paper's ground extraction, and the clusters
FLIC 0 MC finds there. Prints the ranges over the log.

Usage: python scripts/log_stats.py LOG      (e.g. a log written by `flic sample`)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from tqdm import tqdm

from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.runs.pipeline import build_segmenter, prepare


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", type=Path)
    args = parser.parse_args()
    cfg = load_config()
    ds = open_dataset(args.log)
    seg = build_segmenter(cfg, "flic0", "ground", "paper")
    stats = []
    for ref in tqdm(ds.refs(), unit="frame"):
        prep = prepare(ds.load(ref), "ground", cfg.projection)
        labels, ground = seg(prep.image, prep.points)
        valid = int(prep.image.valid.sum())
        stats.append((valid, valid - int(ground.sum()), int(labels.max(initial=0))))
    a = np.array(stats)
    h, w = prep.image.shape
    print(
        f"{len(a)} frames of {w} x {h}: valid pixels {a[:, 0].min()}-{a[:, 0].max()}, "
        f"non-ground (paper) {a[:, 1].min()}-{a[:, 1].max()}, "
        f"FLIC 0 MC clusters {a[:, 2].min()}-{a[:, 2].max()} (median {np.median(a[:, 2]):.0f})"
    )


if __name__ == "__main__":
    main()
