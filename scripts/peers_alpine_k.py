"""ALPINE's k on the synthetic sample: IoU_mu (no-ground setting, oracle classes, 100-point
minimum) of the first three frames for k = 8, 32, 64, with and without box splitting.

Usage: python scripts/peers_alpine_k.py S0/semantickitti   (S0 from `flic sample S0 --frames 20`)
"""

from __future__ import annotations

import sys

import numpy as np

from flic_cli.classes import ground_mask, learning_class
from flic_cli.io import open_dataset
from flic_cli.methods.alpine import Alpine
from flic_cli.methods.base import drop_small
from flic_cli.metrics import match_objects


def main(data: str) -> None:
    ds = open_dataset(data, frames=(0, 3))
    for k in (8, 32, 64):
        for split in (True, False):
            ious: list[float] = []
            for ref in ds.refs():
                frame = ds.load(ref)
                keep = ~ground_mask(frame.labels)
                pts, labels = frame.points[keep], frame.labels[keep]
                raw = Alpine(k=k, split=split).raw(pts, learning_class(labels))
                ious += match_objects(labels, drop_small(raw, 100)).iou.tolist()
            print(f"k {k} split {split}: IoU_mu {100 * np.mean(ious):.2f} ({len(ious)} objects)")


if __name__ == "__main__":
    main(sys.argv[1])
