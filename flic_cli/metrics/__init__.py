"""Evaluation: plain functions over numpy arrays of one frame, or pooled over many.

- :mod:`flic_cli.metrics.instances` -- the paper's protocol (docs/specification.md):
  object matching, IoU, P_x, over- and under-segmentation.

Class ids and groups (things, ground) come from :mod:`flic_cli.classes`.
"""

from flic_cli.metrics.instances import (
    DISTANCE_BANDS,
    IOU_THRESHOLDS,
    MIN_FRAGMENT_POINTS,
    MIN_OBJECT_POINTS,
    ObjectMatches,
    distance_band,
    match_objects,
    score_frame,
    segmentation_stats,
    summarize,
)

__all__ = [
    "DISTANCE_BANDS",
    "IOU_THRESHOLDS",
    "MIN_FRAGMENT_POINTS",
    "MIN_OBJECT_POINTS",
    "ObjectMatches",
    "distance_band",
    "match_objects",
    "score_frame",
    "segmentation_stats",
    "summarize",
]
