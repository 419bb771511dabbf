"""Ground extraction scores: how a remover's ground decision compares with the labels.

Everything here is a plain function over numpy arrays of one frame; :class:`GroundCounts` holds
point counts, so the counts of many frames add up (``sum(counts, GroundCounts())``) and the pooled
scores are computed from the sums, never by averaging per-frame scores.

Conventions
-----------
- The reference: a point is ground when its semantic class is one of
  :data:`flic_cli.classes.GROUND_CLASSES` (road, parking, sidewalk, other-ground, lane-marking,
  terrain), see :func:`flic_cli.classes.ground_mask`.
- Thing-object points are those of :func:`flic_cli.classes.thing_mask` (a thing class and a non-zero
  instance id): the points whose removal costs IoU.
- The decision: a remover marks pixels; a point is taken as ground when its pixel is
  (:func:`point_ground`), or where the remover decides per point, by that decision
  (:func:`flic_cli.ground.base.extract_ground`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from flic_cli.classes import ground_mask, thing_mask
from flic_cli.ground.base import point_ground

__all__ = ["GroundCounts", "ground_counts", "ground_scores", "point_ground"]


@dataclass(frozen=True)
class GroundCounts:
    """Point counts of one frame (or of many, summed with ``+``).

    Attributes
    ----------
    tp : ground-class points taken as ground.
    fp : points of other classes taken as ground.
    fn : ground-class points left (not taken as ground).
    tn : points of other classes left.
    things : thing-object points.
    things_removed : thing-object points taken as ground.
    frames : number of frames counted.
    """

    tp: int = 0
    fp: int = 0
    fn: int = 0
    tn: int = 0
    things: int = 0
    things_removed: int = 0
    frames: int = 0

    def __add__(self, other: GroundCounts) -> GroundCounts:
        return GroundCounts(*(getattr(self, f.name) + getattr(other, f.name) for f in fields(self)))

    @property
    def precision(self) -> float:
        """Share of the points taken as ground that are of a ground class (nan if none taken)."""
        taken = self.tp + self.fp
        return self.tp / taken if taken else float("nan")

    @property
    def recall(self) -> float:
        """Share of the ground-class points taken as ground (nan if there are none)."""
        ref = self.tp + self.fn
        return self.tp / ref if ref else float("nan")

    @property
    def f1(self) -> float:
        """Harmonic mean of precision and recall: ``2 tp / (2 tp + fp + fn)`` (nan if all 0)."""
        den = 2 * self.tp + self.fp + self.fn
        return 2 * self.tp / den if den else float("nan")

    @property
    def things_removed_share(self) -> float:
        """Share of the thing-object points taken as ground (nan if there are none)."""
        return self.things_removed / self.things if self.things else float("nan")


def ground_counts(labels: np.ndarray, on_ground: np.ndarray) -> GroundCounts:
    """Counts of one frame.

    Parameters
    ----------
    labels : (N,) SemanticKITTI ``uint32`` labels of the evaluated points.
    on_ground : (N,) bool, the remover's decision per point (see :func:`point_ground`).

    Returns
    -------
    GroundCounts with ``frames = 1``.
    """
    on_ground = np.asarray(on_ground, dtype=bool)
    if on_ground.shape != np.shape(labels):
        raise ValueError(f"{on_ground.shape[0]} decisions for {np.shape(labels)[0]} labels")
    ref = ground_mask(labels)
    things = thing_mask(labels)
    tp = int(np.count_nonzero(on_ground & ref))
    n_ref = int(np.count_nonzero(ref))
    n_taken = int(np.count_nonzero(on_ground))
    return GroundCounts(
        tp=tp,
        fp=n_taken - tp,
        fn=n_ref - tp,
        tn=on_ground.size - n_ref - n_taken + tp,
        things=int(np.count_nonzero(things)),
        things_removed=int(np.count_nonzero(things & on_ground)),
        frames=1,
    )


def ground_scores(counts: GroundCounts) -> dict[str, float]:
    """Scores in percent, for tables: precision, recall, F1, thing-object points removed.

    Parameters
    ----------
    counts : the counts of one frame or the sum over many.

    Returns
    -------
    dict with ``precision``, ``recall``, ``f1`` and ``things_removed`` (percent, nan where
    undefined) and ``frames``.
    """
    return {
        "precision": 100.0 * counts.precision,
        "recall": 100.0 * counts.recall,
        "f1": 100.0 * counts.f1,
        "things_removed": 100.0 * counts.things_removed_share,
        "frames": counts.frames,
    }
