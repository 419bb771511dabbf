"""``flic segment``: predictions for every selected frame, in SemanticKITTI ``.label`` encoding.

The run: open the data, check ``--out`` and ``--render`` before any work, build the segmenter
once, segment every frame (:class:`SegmentJob` through :class:`flic_cli.runs.frames.FrameLoop`,
in parallel with ``--jobs``), and write the predictions into a staging folder that replaces the
outputs only when the run succeeds (a run stopped by a bad frame writes nothing).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from flic_cli.config import Config
from flic_cli.errors import FlicInputError
from flic_cli.io import open_dataset, write_predictions
from flic_cli.io.atomic import staged_folder
from flic_cli.io.base import FrameRef
from flic_cli.projection import Projection
from flic_cli.range_image import RangeImage
from flic_cli.runs.frames import FrameLoop, Skipped, sort_skipped, write_skipped
from flic_cli.runs.output import check_output_dir
from flic_cli.runs.pipeline import Segmenter, build_segmenter, prepare


@dataclass
class Segmented:
    """One frame's result, as the worker returns it.

    Attributes
    ----------
    labels : (N_scan,) cluster id of every point of the scan as stored (0 = none).
    clusters : number of clusters.
    owned, points : pixels holding a measurement and points of the evaluated set (coverage).
    fallback : the scan's ring recovery failed and a spherical projection was used.
    picture : ``(image, pixel labels per point, ground mask)`` of the frame to render, else None.
    """

    labels: np.ndarray
    clusters: int
    owned: int
    points: int
    fallback: bool
    picture: tuple[RangeImage, np.ndarray, Any] | None = None


@dataclass(frozen=True)
class SegmentJob:
    """Segment one frame (picklable: the dataset and the built segmenter are sent once)."""

    dataset: Any
    segmenter: Segmenter
    setting: str
    projection: Projection
    render: int | None = None

    def __call__(self, ref: FrameRef) -> Segmented:
        prep = prepare(self.dataset.load(ref), self.setting, self.projection)
        labels, ground = self.segmenter(prep.image, prep.points)
        return Segmented(
            prep.scan_labels(labels),
            int(labels.max(initial=0)),
            int(np.count_nonzero(prep.image.ranges)),
            int(prep.image.point_pixel.size),
            self.projection.mode == "rings" and prep.image.projection == "spherical",
            (prep.image, labels, ground) if ref.frame == self.render else None,
        )


@dataclass
class SegmentSummary:
    """What :func:`run_segment` did (``line()`` is what the CLI prints)."""

    frames: int
    points: int
    clusters_per_frame: float
    coverage: float
    out: Path
    fallbacks: int = 0
    skipped: list[Skipped] = field(default_factory=list)
    renders: list[Path] = field(default_factory=list)

    def line(self) -> str:
        text = (
            f"segmented {self.frames} frames, {self.points} points, "
            f"{self.clusters_per_frame:.1f} clusters per frame, "
            f"projection coverage {100 * self.coverage:.1f}%"
        )
        if self.fallbacks:
            text += f", {self.fallbacks} frame(s) projected spherically (ring recovery failed)"
        if self.skipped:
            text += f", skipped {len(self.skipped)} bad frame(s) (skipped.csv)"
        return f"{text} -> {self.out}"


def run_segment(
    data: Path,
    out: Path,
    method: str,
    config: Config,
    setting: str = "ground",
    sequences: list[str] | None = None,
    frames: tuple[int | None, int | None] | None = None,
    ground_remover: str = "own",
    render: int | None = None,
    jobs: int = 1,
    skip_bad: bool = False,
    progress: bool = True,
) -> SegmentSummary:
    """Segment every selected frame and write ``<out>/sequences/NN/predictions/XXXXXX.label``.

    Parameters
    ----------
    data : dataset root, sequence folder or Moosmann log.
    out : output root.
    method : method variant name (``flic14``, ``bogoslavskyi``, ...).
    config : loaded config.
    setting : ``"ground"`` or ``"no-ground"``.
    ground_remover : ``"own"`` or a remover's name (see
        :func:`flic_cli.runs.pipeline.build_segmenter`).
    render : if set, also write ``<out>/render_<seq>_<frame>.png`` for this frame number, which
        must be among the selected frames.
    jobs : processes (see :func:`flic_cli.runs.parallel.imap_frames`).
    skip_bad : go on past frames whose input is bad (listed in ``skipped.csv``).
    progress : show a progress bar.

    Raises
    ------
    FlicInputError
        On bad input, before any work where it can be known (data, options, ``out``).
    """
    ds = open_dataset(data, sequences, frames, require_labels=setting == "no-ground")
    refs = ds.refs()
    out = check_output_dir(Path(out), ds.folders())
    if render is not None and render not in {r.frame for r in refs}:
        shown = sorted({r.frame for r in refs})
        span = f"{shown[0]}..{shown[-1]}" if len(shown) > 1 else str(shown[0])
        raise FlicInputError(None, f"--render {render}: no such frame among the selected ({span})")
    seg = build_segmenter(config, method, setting, ground_remover)
    job = SegmentJob(ds, seg, setting, config.projection, render)
    loop = FrameLoop(job, refs, jobs, None, skip_bad, f"segment {method}", progress)
    n_points = n_clusters = owned = pixels = fallbacks = 0
    renders = []
    with staged_folder(out) as stage:
        for ref, result in loop:
            write_predictions(stage, ref.sequence, ref.frame, result.labels)
            n_points += result.labels.size
            n_clusters += result.clusters
            owned += result.owned
            pixels += result.points
            fallbacks += result.fallback
            if result.picture is not None:
                from flic_cli.plots import render_segmentation

                image, labels, ground = result.picture
                name = f"render_{ref.sequence}_{ref.frame:06d}.png"
                render_segmentation(
                    image,
                    labels,
                    ground,
                    stage / name,
                    title=f"{method}, sequence {ref.sequence} frame {ref.frame}: "
                    f"{result.clusters} clusters",
                )
                renders.append(out / name)
        if loop.skipped:
            write_skipped(stage / "skipped.csv", sort_skipped(loop.skipped))
    done = len(refs) - len(loop.skipped)
    return SegmentSummary(
        done,
        n_points,
        n_clusters / max(done, 1),
        owned / max(pixels, 1),
        out,
        fallbacks,
        sort_skipped(loop.skipped),
        renders,
    )
