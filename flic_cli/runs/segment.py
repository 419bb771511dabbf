"""``flic segment``: predictions for every selected frame, in SemanticKITTI ``.label`` encoding."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from flic_cli.io import open_dataset, write_predictions
from flic_cli.runs.pipeline import make_segmenter, prepare


@dataclass
class SegmentSummary:
    frames: int
    points: int
    clusters_per_frame: float
    coverage: float
    out: Path

    def line(self) -> str:
        return (
            f"segmented {self.frames} frames, {self.points} points, "
            f"{self.clusters_per_frame:.1f} clusters per frame, "
            f"projection coverage {100 * self.coverage:.1f}% -> {self.out}"
        )


def run_segment(
    data: Path,
    out: Path,
    method: str,
    cfg: dict[str, Any],
    setting: str = "ground",
    sequences: list[str] | None = None,
    frames: tuple[int | None, int | None] | None = None,
    ground_remover: str = "own",
    render: int | None = None,
    progress: bool = True,
) -> SegmentSummary:
    """Segment every selected frame and write ``<out>/sequences/NN/predictions/XXXXXX.label``.

    Parameters
    ----------
    data : dataset root, sequence folder or Moosmann log.
    out : output root.
    method : method variant name (``flic14``, ``bogoslavskyi``, ...).
    cfg : loaded config.
    setting : ``"ground"`` or ``"no-ground"``.
    ground_remover : ``"own"``, ``"paper"`` or ``"bogoslavskyi"`` (see ``make_segmenter``).
    render : if set, also write ``<out>/render_<seq>_<frame>.png`` for this frame number.
    """
    ds = open_dataset(data, sequences, frames, require_labels=setting == "no-ground")
    refs = ds.refs()
    seg = make_segmenter(cfg, method, setting, ground_remover)
    n_points = n_clusters = 0
    pixels = owned = 0
    for ref in tqdm(refs, desc=f"segment {method}", unit="frame", disable=not progress):
        prep = prepare(ds.load(ref), setting, cfg.get("projection", {}))
        labels, ground = seg(prep.image, prep.points)
        write_predictions(out, ref.sequence, ref.frame, prep.scan_labels(labels))
        n_points += prep.n_scan
        n_clusters += int(labels.max(initial=0))
        owned += int(np.count_nonzero(prep.image.ranges))
        pixels += prep.image.point_pixel.size
        if render is not None and ref.frame == render:
            from flic_cli.plots import render_segmentation

            render_segmentation(
                prep.image,
                labels,
                ground,
                out / f"render_{ref.sequence}_{ref.frame:06d}.png",
                title=f"{method}, sequence {ref.sequence} frame {ref.frame}: "
                f"{labels.max(initial=0)} clusters (grey = ground)",
            )
    return SegmentSummary(
        len(refs), n_points, n_clusters / max(len(refs), 1), owned / max(pixels, 1), out
    )
