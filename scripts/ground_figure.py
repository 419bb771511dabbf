"""Figure: one labelled frame seen from above, the paper's ground mask beside flic's ``column``.

Every point of the frame is drawn from above (x forward, y left, metres, within ``--extent`` of
the sensor), coloured by what each remover made of it: taken as ground (light grey), kept
(dark grey), and the two errors that cost IoU: points of ground-truth objects taken as ground
(red) and ground-class points left beside the objects (orange). The title of each panel gives
the remover's ground recall and the share of object points it removed in this frame.

Usage::

    python scripts/ground_figure.py ../shared/data/semantickitti --sequence 08 --frame 0 \\
        --out results/ground/ground_masks_08_000000.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from flic_cli.classes import ground_mask, thing_mask  # noqa: E402
from flic_cli.config import load_config  # noqa: E402
from flic_cli.io import open_dataset  # noqa: E402
from flic_cli.metrics.ground import ground_counts, point_ground  # noqa: E402
from flic_cli.runs.pipeline import prepare  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default="../shared/data/semantickitti", type=Path)
    parser.add_argument("--sequence", default="08")
    parser.add_argument("--frame", type=int, default=0)
    parser.add_argument("--removers", default="paper,column")
    parser.add_argument("--extent", type=float, default=30.0, help="metres around the sensor")
    parser.add_argument("--out", type=Path, default=Path("results/ground/ground_masks.png"))
    args = parser.parse_args()

    cfg = load_config()
    ds = open_dataset(args.data)
    ref = next(
        r for r in ds.refs() if r.sequence == args.sequence and r.frame == args.frame
    )  # fmt: skip
    prep = prepare(ds.load(ref), "ground", cfg.projection)
    pts, labels = prep.points, prep.labels
    is_ground, is_thing = ground_mask(labels), thing_mask(labels)
    inside = (np.abs(pts[:, 0]) < args.extent) & (np.abs(pts[:, 1]) < args.extent)
    names = args.removers.split(",")
    fig, axes = plt.subplots(1, len(names), figsize=(7 * len(names), 7.4), squeeze=False)
    for ax, name in zip(axes[0], names, strict=True):
        remover = cfg.remover(name)
        taken = point_ground(prep.image, remover.extract(prep.image, pts).mask)
        counts = ground_counts(labels, taken)
        layers = [
            (taken & ~(is_thing), "#d9d9d9", 0.4, "taken as ground"),
            (~taken & ~is_ground, "#505050", 0.6, "kept"),
            (~taken & is_ground, "#ff9900", 1.2, "ground-class point left"),
            (taken & is_thing, "#e00000", 3.0, "object point taken as ground"),
        ]
        for mask, colour, size, label in layers:
            m = mask & inside
            ax.scatter(pts[m, 1], pts[m, 0], s=size, c=colour, linewidths=0, label=label)
        ax.set_title(
            f"{name}: ground recall {100 * counts.recall:.1f} %, "
            f"object points removed {100 * counts.things_removed_share:.1f} %"
        )
        ax.set_xlim(args.extent, -args.extent)  # y to the left, as seen from above
        ax.set_ylim(-args.extent, args.extent)
        ax.set_aspect("equal")
        ax.set_xlabel("y (m, left)")
        ax.set_ylabel("x (m, forward)")
        ax.legend(loc="lower left", markerscale=6, fontsize=8)
    fig.suptitle(
        f"SemanticKITTI sequence {ref.sequence} frame {ref.frame:06d}, ground setting "
        "(all points); KITTI scans: Geiger et al. 2012, labels: Behley et al. 2019"
    )
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
