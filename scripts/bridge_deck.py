"""Bridge with a *deck link*, measured and not built (results/bridge-cases/README.md, "Decks").

Beyond about 12 m a vehicle's deck -- a hood, a trunk lid -- falls between two beams: the scan
shows the top edge of a low upright face (p, a van's hood front, a car's rear face) and, one row
up, an upright face that rises behind it (q, the cabin's face, the rear pillars), a deck's depth
behind p: 0.7 m for the van of ``scripts/bridge_cases.py``, more than Bridge's link distance
there. A deck link joins p = (r, c) and q = (r - 1, c) where

- both beams look down, and q lies behind p by at most ``deck_max_m`` (horizontal ranges, metres)
  and above the level surface through p (a deck of that depth would be hidden between them);
- the node below p and the node above q are nodes on the same upright faces as p and q: each
  lies higher than the other by more than ``1 / deck_upright`` times their horizontal distance;
- with ``deck_width_m`` > 0, the step runs along at least that many metres of row r (the
  columns of one run of such pairs, at p's range): a vehicle's width, not a bicycle's;
- with ``deck_within``, q's cluster lies within the columns of p's cluster (two columns either
  side): a vehicle's upper body stands within the outline of its lower body as the sensor sees
  it, a wall or a building behind a bicycle reaches beyond it (the clusters are Bridge's, before
  the links and the minimum size; a cluster across the image's first column spans them all).

The links are added to Bridge's graph (its clusters joined where a link joins them: the
components of the graph with the links), then the minimum size applies as in Bridge. The method
kind ``bridge-deck`` is registered from outside flic (:func:`flic_cli.registry.register`), so
the run stays in this process (``--jobs 1``: worker processes would not see the registration).
It measures the class-agnostic labels; ``--semantics`` is not passed.

Usage::

    python scripts/bridge_deck.py DATA OUT [--setting both]   # flic evaluate with bridge and
    # the deck variants below into OUT, then scripts/paired_differences.py OUT

``OUT/links.csv``: the deck links of each variant that join two of Bridge's clusters, in the
no-ground setting: ``variant, truth, class_p, class_q, links, frames, step_min_m, step_max_m,
z_p_median_m`` (``truth``: ``one object`` where p and q are points of one object, ``apart``
where they are of two objects or of an object and something that is none; the classes of p and
q; ``frames``: in how many frames; the shortest and longest step from p to q, horizontal, and the
median height of p, sensor frame, metres).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Annotated

import numpy as np
import pandas as pd
from pydantic import Field
from pydantic.dataclasses import dataclass
from scipy.ndimage import label as runs_of
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from tqdm import tqdm

from flic_cli import registry
from flic_cli.classes import class_name
from flic_cli.component import STRICT
from flic_cli.io.atomic import write_table
from flic_cli.labels import instance, semantic
from flic_cli.methods.base import drop_small, ground_parts, point_weights
from flic_cli.methods.bridge import Bridge, run_bridge

#: The variants measured: name -> (deck_max_m, deck_width_m, deck_within).
VARIANTS = {
    "bridge-deck-06": (0.6, 0.0, False),
    "bridge-deck-08": (0.8, 0.0, False),
    "bridge-deck-10": (1.0, 0.0, False),
    "bridge-deck-08-wide": (0.8, 1.0, False),
    "bridge-deck-10-wide": (1.0, 1.0, False),
    "bridge-deck-08-within": (0.8, 0.0, True),
    "bridge-deck-10-within": (1.0, 0.0, True),
}
#: columns either side of p's cluster that q's cluster may reach with ``deck_within``
WITHIN_PX = 2


def deck_links(
    ranges: np.ndarray,
    elevation: np.ndarray,
    skip: np.ndarray | None,
    deck_max_m: float,
    deck_upright: float = 0.5,
    deck_width_m: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The deck links of a range image (module docstring).

    Parameters
    ----------
    ranges : (H, W) metres, 0 = no measurement.
    elevation : (H,) radians.
    skip : (H, W) bool, pixels that are no nodes (ground), or None.
    deck_max_m : deepest deck, metres (horizontal).
    deck_upright : an upright face's largest horizontal change per unit of height.
    deck_width_m : shortest run of steps along a row, metres (0 = any).

    Returns
    -------
    p, q : flat pixel indices of the linked pairs (q one row above p).
    """
    d = np.asarray(ranges, dtype=np.float64)
    h, w = d.shape
    if h < 4:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    node = d > 0
    if skip is not None:
        node &= ~np.asarray(skip, dtype=bool)
    el = np.asarray(elevation, dtype=np.float64)[:, None]
    x, z = d * np.cos(el), d * np.sin(el)
    # p in rows 2 .. H-2: b (below p) = p + 1, q = p - 1, a (above q) = p - 2
    b, p, q, a = (slice(k, h - 3 + k) for k in (3, 2, 1, 0))
    down = (el[p] < 0) & (el[q] < 0)
    step = x[q] - x[p]
    face_p = (z[p] - z[b]) * deck_upright > np.abs(x[p] - x[b])
    face_q = (z[a] - z[q]) * deck_upright > np.abs(x[a] - x[q])
    ok = node[b] & node[p] & node[q] & node[a] & down & face_p & face_q
    ok &= (step > 0) & (step <= deck_max_m) & (z[q] > z[p])
    if deck_width_m > 0 and ok.any():
        runs, n = runs_of(ok, structure=[[0, 0, 0], [1, 1, 1], [0, 0, 0]])
        sum_x = np.bincount(runs.ravel(), weights=np.where(ok, x[p], 0).ravel(), minlength=n + 1)
        width = sum_x * (2 * np.pi / w)  # columns x their mean range x the column spacing
        width[0] = 0.0
        ok &= width[runs] >= deck_width_m
    rows, cols = np.nonzero(ok)
    flat_p = (rows + 2) * w + cols
    return flat_p, flat_p - w


@dataclass(frozen=True, config=STRICT)
class BridgeDeck(Bridge):
    """Bridge whose graph also has the deck links (module docstring)."""

    deck_max_m: Annotated[float, Field(ge=0, le=5)] = 0.8
    deck_upright: Annotated[float, Field(gt=0, le=5)] = 0.5
    deck_width_m: Annotated[float, Field(ge=0, le=10)] = 0.0
    deck_within: bool = False

    def clusters(self, image, left_out, attached, weights) -> np.ndarray:  # noqa: ANN001
        """Bridge's clusters of the pixels without the minimum size, (H * W,)."""
        return run_bridge(
            image.ranges, image.elevation, self.threshold_m, self.gamma_deg, self.reach_px, 1,
            left_out, weights, None, attached, self.fixed_side_gaps, self.level_tolerance,
            self.level_margin, self.level_cap_m, self.level_support, image.azimuth_offset,
            self.open_holes_px,
        ).reshape(-1)  # fmt: skip

    def links(self, image, left_out, labels) -> tuple[np.ndarray, np.ndarray]:  # noqa: ANN001
        """This variant's deck links (:func:`deck_links`) between two of Bridge's clusters
        (``labels``, :meth:`clusters`), with ``deck_within`` those whose q's cluster lies within
        the columns of p's."""
        p, q = deck_links(
            image.ranges, image.elevation, left_out, self.deck_max_m, self.deck_upright,
            self.deck_width_m,
        )  # fmt: skip
        keep = (labels[p] > 0) & (labels[q] > 0) & (labels[p] != labels[q])
        if self.deck_within and keep.any():
            width = image.ranges.shape[1]
            column = np.arange(labels.size) % width
            has = labels > 0
            first = np.full(int(labels.max()) + 1, width)
            last = np.full(first.size, -1)
            np.minimum.at(first, labels[has], column[has])
            np.maximum.at(last, labels[has], column[has])
            lp, lq = labels[p], labels[q]
            keep &= (first[lq] >= first[lp] - WITHIN_PX) & (last[lq] <= last[lp] + WITHIN_PX)
        return p[keep], q[keep]

    def segment(self, image, points, ground, semantics=None) -> np.ndarray:  # noqa: ANN001
        if semantics is not None:
            raise ValueError("bridge-deck measures class-agnostic labels: run it without semantics")
        left_out, attached = ground_parts(ground)
        weights = point_weights(image)
        labels = self.clusters(image, left_out, attached, weights)
        p, q = self.links(image, left_out, labels)
        if p.size:
            n = int(labels.max()) + 1
            graph = coo_matrix((np.ones(p.size), (labels[p], labels[q])), (n, n))
            comp = connected_components(graph, directed=False)[1]
            labels = np.where(labels > 0, comp[labels] + 1, 0)
        counts = np.ones(labels.size, np.int64) if weights is None else weights.reshape(-1)
        return drop_small(labels, self.min_size, counts)[image.point_pixel]


def deck_joins(data: Path, config: Path) -> pd.DataFrame:
    """The deck links of every variant that join two of Bridge's clusters, in the no-ground
    setting, by what the ground truth says of them (``OUT/links.csv``, module docstring)."""
    from flic_cli.config import load_config
    from flic_cli.io import open_dataset
    from flic_cli.runs.pipeline import prepare

    projection = load_config(config).projection
    dataset = open_dataset(data)
    parts = []
    for ref in tqdm(dataset.refs(), desc="deck links", unit="frame"):
        prep = prepare(dataset.load(ref), "no-ground", projection)
        image = prep.image
        truth = image.pixel_values(prep.labels.astype(np.int64), fill=0).reshape(-1)
        obj, cls = instance(truth) > 0, semantic(truth)
        elevation = np.repeat(image.elevation, image.ranges.shape[1])
        ranges = image.ranges.reshape(-1).astype(np.float64)
        x, z = ranges * np.cos(elevation), ranges * np.sin(elevation)
        labels = BridgeDeck().clusters(image, None, None, point_weights(image))
        for name, (deck_max, width, within) in VARIANTS.items():
            deck = BridgeDeck(deck_max_m=deck_max, deck_width_m=width, deck_within=within)
            p, q = deck.links(image, None, labels)
            same = (truth[p] == truth[q]) & obj[p]
            apart = (truth[p] != truth[q]) & (obj[p] | obj[q])
            for kind, pick in (("one object", same), ("apart", apart)):
                pp, qq = p[pick], q[pick]
                parts.append(pd.DataFrame({
                    "variant": name, "truth": kind,
                    "class_p": [class_name(c) for c in cls[pp]],
                    "class_q": [class_name(c) for c in cls[qq]],
                    "frame": f"{ref.sequence}/{ref.frame}", "step_m": x[qq] - x[pp], "z_p_m": z[pp],
                }))  # fmt: skip
    links = pd.concat(parts, ignore_index=True)
    table = (
        links.groupby(["variant", "truth", "class_p", "class_q"])
        .agg(
            links=("step_m", "size"),
            frames=("frame", "nunique"),
            step_min_m=("step_m", "min"),
            step_max_m=("step_m", "max"),
            z_p_median_m=("z_p_m", "median"),
        )
        .reset_index()
        .round(3)
    )
    return table.sort_values(["variant", "truth", "links"], ascending=[True, True, False])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", type=Path, help="labelled data (flic evaluate's DATA)")
    ap.add_argument("out", type=Path, help="flic evaluate's output folder")
    ap.add_argument("--setting", default="both", help="flic evaluate --setting")
    ap.add_argument("--config", type=Path, help="a config whose [projection] to use")
    args = ap.parse_args()

    from flic_cli.cli.app import app

    registry.register("method", "bridge-deck", registry.Entry(f"{__name__}:BridgeDeck", "deck"))
    text = args.config.read_text() if args.config else ""
    text += "".join(
        f'\n[methods.{name}]\nkind = "bridge-deck"\ndeck_max_m = {g}\ndeck_width_m = {wd}\n'
        f"deck_within = {str(within).lower()}\n"
        for name, (g, wd, within) in VARIANTS.items()
    )
    with tempfile.TemporaryDirectory() as tmp:
        config = Path(tmp) / "deck.toml"
        config.write_text(text)
        evaluate = [
            "evaluate", str(args.data), "--config", str(config), "--methods",
            ",".join(["bridge", *VARIANTS]), "--setting", args.setting,
            "--ground-remover", "column", "--out", str(args.out), "--jobs", "1",
        ]  # fmt: skip
        try:
            app(evaluate, standalone_mode=False)
        except SystemExit as stop:
            if stop.code:
                raise
        links = deck_joins(args.data, config)
    write_table(args.out / "links.csv", links)
    subprocess.run(
        [sys.executable, str(Path(__file__).with_name("paired_differences.py")), str(args.out),
         "--out", str(args.out / "paired.csv")],
        check=True,
    )  # fmt: skip


if __name__ == "__main__":
    main()
