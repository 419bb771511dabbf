"""Tests of flic_cli.metrics.intervals: bootstrap intervals of pooled ratios over frames."""

from __future__ import annotations

import numpy as np
import pytest

from flic_cli.metrics import summarize
from flic_cli.metrics.intervals import (
    Interval,
    frame_sums,
    iou_mu_interval,
    p_mu_interval,
    p_scores,
    pq_interval,
    ratio_interval,
)


def frames_of_objects(rng: np.random.Generator, n_frames: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-object (frame key, IoU) of random frames with 0-11 objects each."""
    counts = rng.integers(0, 12, n_frames)
    keys = np.repeat(np.arange(n_frames), counts)
    return keys, rng.beta(4, 2, keys.size)


def test_interval_contains_the_estimate_and_is_reproducible() -> None:
    keys, ious = frames_of_objects(np.random.default_rng(1), 50)
    sums = frame_sums(keys, ious)
    a = iou_mu_interval(sums["iou_sum"], sums["objects"])
    assert a.estimate == pytest.approx(ious.mean())
    assert a.low < a.estimate < a.high
    assert 0.02 < a.high - a.low < 0.2
    assert a == iou_mu_interval(sums["iou_sum"], sums["objects"])  # fixed seed
    b = iou_mu_interval(sums["iou_sum"], sums["objects"], seed=1)
    assert b.estimate == a.estimate and (b.low, b.high) != (a.low, a.high)
    assert b.low == pytest.approx(a.low, abs=0.01) and b.high == pytest.approx(a.high, abs=0.01)
    p = p_mu_interval(sums["p_sum"], sums["objects"])
    assert p.estimate == pytest.approx(summarize(ious)["p_mu"])
    assert p.low < p.estimate < p.high
    narrow = ratio_interval(sums["iou_sum"], sums["objects"], confidence=0.5)
    assert a.low < narrow.low < narrow.high < a.high


def test_coverage_of_a_known_ratio() -> None:
    """About 95% of intervals from independent data sets hold the true ratio (0.6)."""
    rng = np.random.default_rng(5)
    hits = 0
    for _ in range(60):
        objects = rng.integers(1, 10, 40)
        iou_sum = np.array([rng.beta(3, 2, k).sum() for k in objects])  # mean 0.6
        iv = ratio_interval(iou_sum, objects, n_resamples=999)
        hits += iv.low <= 0.6 <= iv.high
    assert 51 <= hits <= 60


def test_degenerate_cases() -> None:
    nan = Interval(float("nan"), float("nan"), float("nan"), 0)
    got = ratio_interval(np.zeros(3), np.zeros(3))  # no objects at all
    assert np.isnan([got.estimate, got.low, got.high]).all() and got.frames == 0
    assert np.isnan(ratio_interval([], []).estimate) and repr(nan)
    one = ratio_interval([3.0], [4.0])  # one frame: estimate, no interval
    assert one.estimate == 0.75 and np.isnan(one.low) and np.isnan(one.high) and one.frames == 1
    same = ratio_interval([1.5] * 20, [2] * 20)  # all frames identical
    assert (same.estimate, same.low, same.high) == (0.75, 0.75, 0.75)
    prop = ratio_interval([1, 2, 3, 4], [2, 4, 6, 8])  # every frame the same ratio
    assert (prop.low, prop.high) == (0.5, 0.5)


def test_frames_without_objects_are_left_out() -> None:
    keys, ious = frames_of_objects(np.random.default_rng(2), 30)
    s = frame_sums(keys, ious)
    with_empty = ratio_interval(np.r_[s["iou_sum"], 0, 0, 0], np.r_[s["objects"], 0, 0, 0])
    assert with_empty == ratio_interval(s["iou_sum"], s["objects"])
    assert with_empty.frames == s["frame"].size


def test_two_frames_give_an_interval() -> None:
    iv = ratio_interval([1.0, 2.0], [2, 2])
    assert iv.low <= iv.estimate <= iv.high and np.isfinite([iv.low, iv.high]).all()


def test_frame_sums_and_p_scores_by_hand() -> None:
    keys = np.array(["08/000002", "00/000001", "08/000002", "00/000001", "00/000001"])
    ious = np.array([0.5, 1.0, 0.0, 0.74, 0.75])
    np.testing.assert_allclose(p_scores(ious), [0.1, 1.0, 0.0, 0.5, 0.6])
    s = frame_sums(keys, ious)
    assert s["frame"].tolist() == ["00/000001", "08/000002"]
    np.testing.assert_allclose(s["iou_sum"], [2.49, 0.5])
    np.testing.assert_allclose(s["p_sum"], [2.1, 0.1])
    assert s["objects"].tolist() == [3, 2]
    with pytest.raises(ValueError, match="differ"):
        frame_sums(keys[:2], ious)


def test_pq_interval() -> None:
    rng = np.random.default_rng(3)
    tp, fp, fn = rng.integers(0, 8, 25), rng.integers(0, 3, 25), rng.integers(0, 3, 25)
    iou_sum = tp * rng.uniform(0.6, 0.9, 25)
    iv = pq_interval(iou_sum, tp, fp, fn)
    assert iv.estimate == pytest.approx(iou_sum.sum() / (tp.sum() + fp.sum() / 2 + fn.sum() / 2))
    assert iv.low < iv.estimate < iv.high


def test_bad_input() -> None:
    with pytest.raises(ValueError, match="one length"):
        ratio_interval([1, 2], [1])
    with pytest.raises(ValueError, match=">= 0"):
        ratio_interval([1, 2], [1, -1])
