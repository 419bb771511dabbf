"""The per-frame worker of ``flic evaluate`` and ``flic sweep-threshold``.

:class:`ScoreJob` holds what a run sends to its workers once (the segmenters built from the config
and the projection); called on a frame reference it reads the frame once, prepares it once per
setting, extracts each ground mask once, runs every method and scores the labels
(:func:`flic_cli.metrics.score_frame`: object matches and segmentation statistics, and
:func:`flic_cli.metrics.panoptic.agnostic_panoptic_counts`). It returns
small per-object and per-frame records (:class:`FrameScores`), never point clouds.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from flic_cli.classes import class_name
from flic_cli.errors import FlicInputError
from flic_cli.ground.base import Ground
from flic_cli.io.base import Dataset, Frame, FrameRef
from flic_cli.metrics import distance_band, score_frame
from flic_cli.metrics.entropy import object_ids, segmentation_entropy
from flic_cli.metrics.ground import ground_counts
from flic_cli.metrics.panoptic import agnostic_panoptic_counts
from flic_cli.projection import Projection
from flic_cli.runs.pipeline import (
    Prepared,
    Segmenter,
    prepare,
    prepare_semantic,
    prepared_semantics,
    scan_semantics,
    segment_semantic,
)

#: Columns of the per-object records (``per_object.csv``).
OBJECT_COLUMNS: tuple[str, ...] = (
    "method",
    "setting",
    "sequence",
    "frame",
    "instance",
    "class",
    "class_name",
    "points",
    "distance_m",
    "band",
    "cluster",
    "overlap",
    "iou",
)

#: Columns of the per-frame records (``per_frame.csv``).
FRAME_COLUMNS: tuple[str, ...] = (
    "method",
    "setting",
    "sequence",
    "frame",
    "points",
    "clusters",
    "objects",
    "over_segmented",
    "under_segmented",
    "seconds",
    "ground_seconds",
    "pq_tp",
    "pq_fp",
    "pq_fn",
    "pq_iou_sum",
    "ose",
    "use",
)

#: Columns of the per-frame ground-extraction records (ground setting, one row per remover).
GROUND_COLUMNS: tuple[str, ...] = (
    "remover",
    "sequence",
    "frame",
    "tp",
    "fp",
    "fn",
    "tn",
    "things",
    "things_removed",
    "seconds",
)

#: Columns of the per-class panoptic counts with oracle semantics (``--semantics oracle``).
PANOPTIC_COLUMNS: tuple[str, ...] = (
    "method",
    "sequence",
    "frame",
    "class",
    "tp",
    "fp",
    "fn",
    "iou_sum",
    "sem_tp",
    "sem_fp",
    "sem_fn",
)


@dataclass
class FrameScores:
    """One frame's records as column lists (keys :data:`OBJECT_COLUMNS`, :data:`FRAME_COLUMNS`)."""

    sequence: str
    frame: int
    objects: dict[str, list] = field(default_factory=lambda: {c: [] for c in OBJECT_COLUMNS})
    frames: dict[str, list] = field(default_factory=lambda: {c: [] for c in FRAME_COLUMNS})
    ground: dict[str, list] = field(default_factory=lambda: {c: [] for c in GROUND_COLUMNS})
    panoptic: dict[str, list] | None = None

    def tables(self) -> dict[str, tuple[tuple[str, ...], dict[str, list]]]:
        """The records by part name, with their columns (the ``frames`` part last)."""
        out = {
            "objects": (OBJECT_COLUMNS, self.objects),
            "ground": (GROUND_COLUMNS, self.ground),
            "frames": (FRAME_COLUMNS, self.frames),
        }
        if self.panoptic is not None:
            out["panoptic"] = (PANOPTIC_COLUMNS, self.panoptic)
        return out


def load_labelled_frame(dataset: Dataset, ref: FrameRef) -> Frame:
    """Read a frame with its ground-truth labels through its dataset (in a worker).

    Raises
    ------
    FlicInputError
        When the frame has no labels, or cannot be read.
    """
    frame = dataset.load(ref)
    if frame.labels is None:
        raise FlicInputError(
            ref.path,
            "has no ground-truth labels: evaluation needs labelled data (e.g. SemanticKITTI "
            "labels/<frame>.label)",
        )
    return frame


@dataclass(frozen=True)
class ScoreJob:
    """Score methods on a frame, in one or both settings (picklable: sent to workers once).

    Attributes
    ----------
    dataset : the frames' dataset (they are read through it).
    segmenters : per setting (``"no-ground"``, ``"ground"``), the segmenters to run.
    projection : how scans become range images.
    oracle : also score every method with oracle semantics: its clusters of the ground truth's
        thing-class points, per class, the way semantic-kitti-api scores
        ``flic segment --semantics oracle`` (:func:`flic_cli.metrics.panoptic.panoptic_counts`).
    """

    dataset: Dataset
    segmenters: tuple[tuple[str, tuple[Segmenter, ...]], ...]
    projection: Projection
    oracle: bool = False

    def __call__(self, ref: FrameRef) -> FrameScores:
        frame = load_labelled_frame(self.dataset, ref)
        out = FrameScores(ref.sequence, ref.frame)
        for setting, segmenters in self.segmenters:
            prep = prepare(frame, setting, self.projection)
            grounds = GroundCache(prep)
            classes = prepared_semantics(prep)  # the ground truth's, for methods that need them
            for seg in segmenters:
                ground, ground_seconds = grounds.get(seg)
                start = time.perf_counter()
                labels = seg.cluster(prep.image, prep.points, ground, classes)
                seconds = time.perf_counter() - start + ground_seconds
                add_scores(out, seg.name, setting, prep, labels, seconds, ground_seconds)
            grounds.add_records(out)
        if self.oracle:
            out.panoptic = oracle_panoptic(frame, self.segmenters[0][1], self.projection)
        return out


def oracle_panoptic(
    frame: Frame, segmenters: tuple[Segmenter, ...], projection: Projection
) -> dict[str, list]:
    """Per-class panoptic counts of every method with oracle semantics, on one frame.

    The prediction is exactly what ``flic segment --semantics oracle`` writes (the same
    :func:`flic_cli.runs.pipeline.prepare_semantic` and :func:`flic_cli.semantics.combine`), and
    it is scored against the labels of every point of the scan as stored.
    """
    from flic_cli.metrics.panoptic import panoptic_counts
    from flic_cli.semantics import combine

    semantics = scan_semantics(frame, "oracle")
    gt = frame.labels_as_stored()
    assert gt is not None  # load_labelled_frame guarantees labels
    prep = prepare_semantic(frame, semantics, projection)
    rows: dict[str, list] = {c: [] for c in PANOPTIC_COLUMNS}
    for seg in segmenters:
        labels = segment_semantic(seg.method, prep, semantics)
        counts = panoptic_counts(gt, combine(semantics, prep.scan_labels(labels)))
        n = len(counts)
        rows["method"] += [seg.name] * n
        rows["sequence"] += [frame.ref.sequence] * n
        rows["frame"] += [frame.ref.frame] * n
        rows["class"] += list(range(n))
        for key, values in counts.as_dict().items():
            rows[key] += values.tolist()
    return rows


class GroundCache:
    """Each remover's ground step on one prepared frame, run once and timed.

    Its time is counted in every method that uses it (as if each method ran alone).
    """

    def __init__(self, prep: Prepared) -> None:
        self.prep = prep
        self.steps: dict[str | None, tuple[Ground | None, float]] = {}

    def get(self, seg: Segmenter) -> tuple[Ground | None, float]:
        """The ground step of ``seg``'s remover (None without one) and its time."""
        if seg.ground_name not in self.steps:
            start = time.perf_counter()
            ground = seg.ground_step(self.prep.image, self.prep.points)
            self.steps[seg.ground_name] = (ground, time.perf_counter() - start)
        return self.steps[seg.ground_name]

    def add_records(self, out: FrameScores) -> None:
        """Append each remover's ground scores of this frame (against the ground classes)."""
        assert self.prep.labels is not None
        for name, (ground, seconds) in self.steps.items():
            if name is None or ground is None:
                continue
            counts = ground_counts(self.prep.labels, ground.on_ground)
            row = {"remover": name, "sequence": self.prep.ref.sequence,
                   "frame": self.prep.ref.frame, **dataclasses.asdict(counts),
                   "seconds": round(seconds, 6)}  # fmt: skip
            for key in GROUND_COLUMNS:
                out.ground[key].append(row[key])


def add_scores(
    out: FrameScores,
    method: str,
    setting: str,
    prep: Prepared,
    labels: np.ndarray,
    seconds: float,
    ground_seconds: float = 0.0,
) -> None:
    """Append one method's per-object and per-frame records of one prepared frame.

    ``seconds`` is the method's time with its ground extraction, ``ground_seconds`` the latter's
    part (extracted once per remover and frame, counted in every method that uses it).
    """
    assert prep.labels is not None  # load_labelled_frame guarantees labels
    matches, stats = score_frame(prep.labels, labels, prep.points)
    pq = agnostic_panoptic_counts(prep.labels, labels)
    ose, use = segmentation_entropy(object_ids(prep.labels), labels)
    n = len(matches)
    obj = out.objects
    obj["method"] += [method] * n
    obj["setting"] += [setting] * n
    obj["sequence"] += [prep.ref.sequence] * n
    obj["frame"] += [prep.ref.frame] * n
    obj["instance"] += matches.instance.tolist()
    obj["class"] += matches.semantic.tolist()
    obj["class_name"] += [class_name(c) for c in matches.semantic]
    obj["points"] += matches.n_points.tolist()
    obj["distance_m"] += np.round(matches.distance, 3).tolist()
    obj["band"] += distance_band(matches.distance).tolist()
    obj["cluster"] += matches.cluster.tolist()
    obj["overlap"] += matches.overlap.tolist()
    obj["iou"] += matches.iou.tolist()
    for key, value in (
        ("method", method),
        ("setting", setting),
        ("sequence", prep.ref.sequence),
        ("frame", prep.ref.frame),
        ("points", int(prep.points.shape[0])),
        ("clusters", stats["clusters"]),
        ("objects", stats["objects"]),
        ("over_segmented", stats["over_segmented"]),
        ("under_segmented", stats["under_segmented"]),
        ("seconds", round(seconds, 6)),
        ("ground_seconds", round(ground_seconds, 6)),
        ("pq_tp", int(pq.tp[0])),
        ("pq_fp", int(pq.fp[0])),
        ("pq_fn", int(pq.fn[0])),
        ("pq_iou_sum", float(pq.iou_sum[0])),
        ("ose", round(ose, 6)),
        ("use", round(use, 6)),
    ):
        out.frames[key].append(value)
