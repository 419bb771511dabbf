"""``flic segment``: predictions for every selected frame, in the data format's own encoding.

The run: open the data, check ``--out``, ``--render`` and ``--semantics`` before any work, build the
segmenter once, segment every frame (:class:`SegmentJob` through
:class:`flic_cli.runs.frames.FrameLoop`, in parallel with ``--jobs``), and write the predictions
into a staging folder that replaces the outputs only when the run succeeds (a run stopped by a bad
frame writes nothing).

Predictions: SemanticKITTI ``<out>/sequences/NN/predictions/XXXXXX.label`` (cluster id in the upper
16 bits, the semantic class in the lower: 0, or with ``--semantics`` the given classes, see
:mod:`flic_cli.semantics`); Moosmann logs ``<out>/<log>/scanNNNNN.label.png`` (16-bit label image).
With ``--semantics`` only the points of thing classes are clustered (semantic network +
clustering), without a ground remover.
"""

from __future__ import annotations

import time
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from flic_cli import registry
from flic_cli.errors import FlicInputError
from flic_cli.ground.base import Ground
from flic_cli.io import open_dataset
from flic_cli.io.atomic import staged_folder
from flic_cli.io.base import FrameRef
from flic_cli.io.ply import write_ply
from flic_cli.projection import Projection
from flic_cli.runs import latency
from flic_cli.runs.frames import FrameLoop, Skipped, sort_skipped, write_skipped
from flic_cli.runs.output import check_output_dir, holding_out_lock
from flic_cli.runs.pipeline import (
    OWN,
    Prepared,
    Segmenter,
    build_segmenter,
    prepare,
    prepare_semantic,
    scan_semantics,
    segment_semantic,
)
from flic_cli.runs.spec import SegmentRun
from flic_cli.sensor_params import for_dataset

#: ``--semantics`` values besides a folder of a semantic network's predictions.
SEMANTICS = ("none", "oracle")

#: ``--export`` formats (``mcap`` / ``bag``: a ROS 2 bag of PointCloud2 clusters, bag input only).
EXPORTS = ("ply", "mcap", "bag")

#: Formats whose frames are revolutions of a recording: the run reports the latency per frame.
STREAMS = latency.STREAMS


@dataclass
class Segmented:
    """One frame's result, as the worker returns it.

    Attributes
    ----------
    prep : the prepared frame (range image, evaluated points and their labels).
    labels : (N,) cluster id of every evaluated point (0 = none).
    ground : the ground step's result (its mask and its ground points), or None.
    semantics : (N_scan,) classes written with the prediction (``--semantics``), or None.
    """

    prep: Prepared
    labels: np.ndarray
    ground: Ground | None
    semantics: np.ndarray | None = None
    extra: dict[str, Any] | None = None
    latency_ms: float = 0.0

    @property
    def clusters(self) -> int:
        return int(self.labels.max(initial=0))

    def ground_points(self) -> np.ndarray:
        """(N,) bool, the evaluated points taken as ground."""
        if self.ground is None:
            return np.zeros(self.labels.shape[0], dtype=bool)
        return self.ground.on_ground


@dataclass(frozen=True)
class SegmentJob:
    """Segment one frame (picklable: the dataset and the built segmenter are sent once).

    Attributes
    ----------
    semantics : None (no semantics), ``"oracle"`` or a folder of a network's predictions.
    """

    dataset: Any
    segmenter: Segmenter
    setting: str
    projection: Projection
    semantics: str | None = None

    def __call__(self, ref: FrameRef) -> Segmented:
        start = time.perf_counter()  # latency: decode + range image + ground + cluster
        frame = self.dataset.load(ref)
        extra = frame.export_fields() if hasattr(frame, "export_fields") else None
        if self.semantics is None:
            prep = prepare(frame, self.setting, self.projection)
            labels, ground = self.segmenter.run(prep.image, prep.points)
            ms = (time.perf_counter() - start) * 1e3
            return Segmented(prep, labels, ground, extra=extra, latency_ms=ms)
        semantics = scan_semantics(frame, self.semantics)
        prep = prepare_semantic(frame, semantics, self.projection)
        labels = segment_semantic(self.segmenter.method, prep, semantics)
        ms = (time.perf_counter() - start) * 1e3
        return Segmented(prep, labels, None, semantics, extra=extra, latency_ms=ms)


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
    latency: str | None = None
    exports: list[Path] = field(default_factory=list)

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
        if self.latency:
            text += f"; {self.latency}"
        return f"{text} -> {self.out}"


@holding_out_lock
def run_segment(spec: SegmentRun) -> SegmentSummary:
    """Segment every selected frame and write its prediction in the data format's own encoding
    (SemanticKITTI ``<out>/sequences/NN/predictions/XXXXXX.label``).

    Parameters
    ----------
    spec : what to segment and how (:class:`flic_cli.runs.spec.SegmentRun`; the selection's
        setting defaults to ``"ground"``, its ground remover to ``"own"``).

    Raises
    ------
    FlicInputError
        On bad input, before any work where it can be known (data, options, ``out``).
    """
    sel = spec.selection
    config = sel.loaded_config()
    setting = sel.setting_or("ground")
    method, render, export = spec.method, spec.render, spec.export
    wanted = _semantics_mode(spec.semantics)
    bad_export = [e for e in export if e not in EXPORTS]
    if bad_export:
        raise FlicInputError(None, f"--export {bad_export[0]}: one of {', '.join(EXPORTS)}")
    ds = open_dataset(
        sel.data,
        sel.sequences,
        sel.frames,
        require_labels=setting == "no-ground" or wanted == "oracle",
        reader=sel.reader,
    )
    if wanted is not None and not ds.point_semantics:
        raise FlicInputError(
            sel.data, f"--semantics: {ds.format} predictions carry no semantic classes per point"
        )
    refs = ds.refs()
    out = check_output_dir(Path(spec.out), ds.folders())
    if render is not None and render not in {r.frame for r in refs}:
        shown = sorted({r.frame for r in refs})
        span = f"{shown[0]}..{shown[-1]}" if len(shown) > 1 else str(shown[0])
        raise FlicInputError(None, f"--render {render}: no such frame among the selected ({span})")
    own_exports = {x for e in registry.FORMATS.values() for x in e.exports}
    needs_own = [e for e in export if e in own_exports]
    if needs_own and needs_own[0] not in registry.FORMATS[ds.format].exports:
        raise FlicInputError(sel.data, f"--export {needs_own[0]} needs a bag or MCAP input")
    config = for_dataset(config, ds, refs)  # the sensor's derived parameters
    seg = build_segmenter(config, method, setting, sel.remover_or(OWN))
    job = SegmentJob(ds, seg, setting, config.projection, wanted)
    loop = FrameLoop(job, refs, sel.jobs, None, sel.skip_bad, f"segment {method}", sel.progress)
    n_points = n_clusters = owned = pixels = fallbacks = 0
    renders = []
    latencies: list[float] = []
    with staged_folder(out) as stage, ExitStack() as writers:
        bag_writers = [_bag_writer(writers, stage, ds, e, wanted is not None) for e in needs_own]
        for ref, result in loop:
            latencies.append(result.latency_ms)
            for w in bag_writers:
                _write_cloud(w, result)
            prep = result.prep
            ds.write_prediction(
                stage, ref, prep.scan_labels(result.labels), prep.image, result.semantics
            )
            if "ply" in export:
                write_ply(
                    ds.export_path(stage, ref, ".ply"),
                    prep.points,
                    result.labels,
                    result.ground_points(),
                )
            n_points += prep.n_scan
            n_clusters += result.clusters
            owned += int(np.count_nonzero(prep.image.ranges))
            pixels += int(prep.image.point_pixel.size)
            fallbacks += config.projection.mode == "rings" and prep.image.projection == "spherical"
            if ref.frame == render:
                renders += _render(
                    stage,
                    ref,
                    result,
                    f"{method}, sequence {ref.sequence} "
                    f"frame {ref.frame}: {result.clusters} clusters",
                )
        if loop.skipped:
            write_skipped(stage / "skipped.csv", sort_skipped(loop.skipped))
        writers.close()  # the bags are complete before the stage moves into place
    done = len(refs) - len(loop.skipped)
    return SegmentSummary(
        done,
        n_points,
        n_clusters / max(done, 1),
        owned / max(pixels, 1),
        out,
        fallbacks,
        sort_skipped(loop.skipped),
        [out / name for name in renders],
        latency_line(latencies) if ds.format in STREAMS and latencies and sel.jobs == 1 else None,
        [out / w.path.name for w in bag_writers],
    )


def latency_line(latencies_ms: list[float]) -> str:
    """The run's latency per revolution (:func:`flic_cli.runs.latency.summary_line`)."""
    from flic_cli.runs.latency import summary_line

    return summary_line("segment", np.asarray(latencies_ms))


def _bag_writer(stack: ExitStack, stage: Path, ds: Any, storage: str, with_label: bool) -> Any:
    """An open :class:`flic_cli.io.bag_writer.CloudBagWriter` for ``--export mcap|bag``."""
    from flic_cli.io.bag_writer import CloudBagWriter, export_folder

    path = export_folder(stage, ds.root, storage)
    return stack.enter_context(CloudBagWriter(path, storage, "/flic/clusters", with_label))


def _write_cloud(writer: Any, result: Segmented) -> None:
    """One frame's PointCloud2 of clusters, with the input's stamp and frame id."""
    extra = result.extra or {}
    label = None
    if writer.with_label and result.semantics is not None:
        sem = result.semantics
        keep = result.prep.keep
        label = sem if keep is None else sem[keep]
    writer.write(
        int(extra.get("stamp_ns", 0)),
        str(extra.get("frame_id", "")),
        result.prep.points,
        result.labels,
        extra.get("intensity"),
        label,
    )


def _semantics_mode(semantics: str) -> str | None:
    """``--semantics``: None for ``none``, ``"oracle"``, or the folder (which must exist)."""
    if semantics == "none":
        return None
    if semantics == "oracle":
        return semantics
    if not Path(semantics).is_dir():
        raise FlicInputError(
            semantics, "--semantics: neither none, oracle nor a folder of semantic predictions"
        )
    return str(semantics)


def _render(stage: Path, ref: FrameRef, result: Segmented, title: str) -> list[str]:
    """Draw a frame: its range image and its bird's-eye / 3D views; the file names."""
    from flic_cli.plots import render_frame_views, render_segmentation

    names = [
        f"render_{ref.sequence}_{ref.frame:06d}.png",
        f"views_{ref.sequence}_{ref.frame:06d}.png",
    ]
    prep = result.prep
    mask = None if result.ground is None else result.ground.mask
    render_segmentation(prep.image, result.labels, mask, stage / names[0], title=title)
    render_frame_views(
        stage / names[1],
        prep.points,
        result.labels,
        prep.labels,
        result.ground_points(),
        title=title,
    )
    return names
