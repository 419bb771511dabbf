"""OSE / USE against values computed by hand, and Continuous Clustering's ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flic_cli.labels import encode
from flic_cli.metrics.entropy import (
    continuous_clustering_ground_truth,
    object_ids,
    segmentation_entropy,
)


def test_hand_computed_frame() -> None:
    gt = np.array([1, 1, 1, 1, 2, 2, 0, 0])
    pred = np.array([5, 5, 7, 0, 7, 7, 7, 5])
    ose, use = segmentation_entropy(gt, pred)
    # g=1: d = 5, 5, 7, 0 -> 1/2, 1/4, 1/4 (label 0 counts); g=2: all in 7 -> 0
    assert ose == pytest.approx(-(0.5 * math.log(0.5) + 2 * 0.25 * math.log(0.25)))
    # d=5: g = 1, 1, 0 -> 2/3, 1/3; d=7: g = 1, 2, 2, 0 -> 1/4, 1/2, 1/4 (g = 0 counts)
    use_5 = -(2 / 3 * math.log(2 / 3) + 1 / 3 * math.log(1 / 3))
    use_7 = -(0.5 * math.log(0.5) + 2 * 0.25 * math.log(0.25))
    assert use == pytest.approx(use_5 + use_7)


def test_clusters_without_ground_truth_and_unclustered_points() -> None:
    # cluster 9 holds only background points: left out of USE; unclustered points are no cluster
    gt = np.array([3, 3, 0, 0, 0])
    pred = np.array([4, 4, 9, 9, 0])
    assert segmentation_entropy(gt, pred) == (0.0, 0.0)
    # a segment left entirely unclustered: one label (0) -> OSE 0, and no cluster -> USE 0
    assert segmentation_entropy(np.array([1, 1]), np.array([0, 0])) == (0.0, 0.0)
    # a segment split in two equal halves, one of them unclustered: OSE = ln 2
    ose, use = segmentation_entropy(np.array([1, 1, 1, 1]), np.array([2, 2, 0, 0]))
    assert ose == pytest.approx(math.log(2)) and use == 0.0


def test_entropy_sums_over_segments() -> None:
    # two identical objects, each split in two: twice one object's OSE (a sum, not a mean)
    one = segmentation_entropy(np.array([1, 1, 1]), np.array([1, 1, 2]))[0]
    two = segmentation_entropy(np.array([1, 1, 1, 2, 2, 2]), np.array([1, 1, 2, 3, 3, 4]))[0]
    assert two == pytest.approx(2 * one) and one > 0


def test_brute_force_on_random_frames() -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        gt = rng.integers(0, 4, 60)
        pred = rng.integers(0, 5, 60)
        ose = 0.0
        for g in set(gt.tolist()) - {0}:
            sel = pred[gt == g]
            for d in set(sel.tolist()):
                f = np.mean(sel == d)
                ose -= f * math.log(f)
        use = 0.0
        for d in set(pred.tolist()) - {0}:
            sel = gt[pred == d]
            if not (sel != 0).any():
                continue
            for g in set(sel.tolist()):
                f = np.mean(sel == g)
                use -= f * math.log(f)
        assert segmentation_entropy(gt, pred) == pytest.approx((ose, use))


def test_object_ids_are_the_protocols_objects() -> None:
    car = encode(np.full(120, 10), np.full(120, 1))
    small_car = encode(np.full(50, 10), np.full(50, 2))
    building = encode(np.full(200, 50), np.zeros(200, dtype=int))
    ids = object_ids(np.concatenate([car, small_car, building]))
    assert (ids[:120] == 1).all() and (ids[120:] == 0).all()


def test_continuous_clustering_ground_truth() -> None:
    rng = np.random.default_rng(1)
    a = rng.normal(0, 0.1, (30, 3))
    b = rng.normal(0, 0.1, (30, 3)) + [5, 0, 0]  # same label, 5 m away: a segment of its own
    c = rng.normal(0, 0.1, (5, 3)) + [9, 0, 0]  # same label, 5 points: under 10 -> 0
    road = rng.normal(0, 0.1, (40, 3)) + [0, 9, 0]
    pts = np.vstack([a, b, c, road])
    labels = np.concatenate(
        [encode(np.full(65, 50), np.zeros(65, dtype=int)), np.full(40, 40, np.uint32)]
    )
    gt = continuous_clustering_ground_truth(pts, labels)
    assert len(set(gt[:30])) == 1 and len(set(gt[30:60])) == 1 and gt[0] != gt[30] != 0
    assert (gt[60:] == 0).all()
