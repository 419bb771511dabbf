"""Ground extraction scores on tiny hand-computed cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flic_cli.metrics.ground import GroundCounts, ground_counts, ground_scores, point_ground
from flic_cli.range_image import RangeImage


def _labels(semantic, instance=None):
    semantic = np.asarray(semantic, dtype=np.uint32)
    instance = np.zeros_like(semantic) if instance is None else np.asarray(instance, np.uint32)
    return semantic | (instance << 16)


def test_counts_of_a_hand_made_frame():
    # points: road, road, sidewalk, terrain, car#1, car#1, building, car (no instance id)
    labels = _labels([40, 40, 48, 72, 10, 10, 50, 10], [0, 0, 0, 0, 1, 1, 0, 0])
    taken = np.array([1, 1, 0, 1, 1, 0, 1, 1], dtype=bool)
    c = ground_counts(labels, taken)
    assert c == GroundCounts(tp=3, fp=3, fn=1, tn=1, things=2, things_removed=1, frames=1)
    assert c.precision == pytest.approx(3 / 6)
    assert c.recall == pytest.approx(3 / 4)
    assert c.f1 == pytest.approx(2 * 3 / (2 * 3 + 3 + 1))
    assert c.things_removed_share == pytest.approx(1 / 2)
    s = ground_scores(c)
    assert s["precision"] == pytest.approx(50.0)
    assert s["recall"] == pytest.approx(75.0)
    assert s["f1"] == pytest.approx(100 * 6 / 10)
    assert s["things_removed"] == pytest.approx(50.0)
    assert s["frames"] == 1


def test_counts_add_up_and_pooled_scores_are_not_means_of_frame_scores():
    a = ground_counts(_labels([40, 40, 50]), np.array([1, 1, 0], bool))  # P 1, R 1
    b = ground_counts(_labels([40, 50, 50, 50]), np.array([0, 1, 1, 1], bool))  # P 0, R 0
    pooled = a + b
    assert pooled == GroundCounts(tp=2, fp=3, fn=1, tn=1, things=0, things_removed=0, frames=2)
    assert pooled.precision == pytest.approx(2 / 5)  # the mean of per-frame precisions is 1/2
    assert pooled.recall == pytest.approx(2 / 3)
    assert sum([a, b], GroundCounts()) == pooled


def test_undefined_scores_are_nan():
    c = ground_counts(_labels([50, 51]), np.zeros(2, bool))
    assert math.isnan(c.precision) and math.isnan(c.recall) and math.isnan(c.f1)
    assert math.isnan(c.things_removed_share)
    assert c.tn == 2


def test_length_mismatch_is_an_error():
    with pytest.raises(ValueError):
        ground_counts(_labels([40, 40]), np.zeros(3, bool))


def test_point_ground_takes_the_pixel_decision_and_none_without_a_pixel():
    ground = np.array([[True, False], [False, True]])
    image = RangeImage(
        np.ones((2, 2), np.float32), np.zeros(2), np.array([0, 0, 3, 1, -1]), "spherical"
    )
    assert point_ground(image, ground).tolist() == [True, True, True, False, False]
    dense = RangeImage(np.ones((2, 2), np.float32), np.zeros(2), np.array([3, 2]), "rings")
    assert point_ground(dense, ground).tolist() == [True, False]
