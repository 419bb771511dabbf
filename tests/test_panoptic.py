"""Tests of flic_cli.metrics.panoptic: semantic-kitti-api's PQ on hand-built frames.

The reference numbers of ``test_he_et_al_example`` are those semantic-kitti-api prints for its
own example (``auxiliary/eval_np.py``, the example of Kirillov et al.'s panoptic paper); the
brute-force reference below re-implements ``PanopticEval.addBatchPanoptic`` loop by loop.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import lab

from flic_cli.classes import (
    CLASS_NAMES,
    LEARNING_MAP,
    LEARNING_NAMES,
    LEARNING_STUFF,
    LEARNING_THINGS,
    THING_CLASSES,
    learning_class,
)
from flic_cli.metrics.panoptic import (
    PanopticCounts,
    agnostic_panoptic_counts,
    agnostic_scores,
    class_scores,
    panoptic_counts,
    panoptic_summary,
    pq_sq_rq,
    segment_counts,
)

CAR, BICYCLE, PERSON, ROAD, BUILDING, LANE, OTHER_STRUCTURE, MOVING_CAR = (
    10, 11, 30, 40, 50, 60, 52, 252,
)  # fmt: skip
L_CAR, L_ROAD, L_BUILDING = 1, 9, 13


def runs(*parts: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray]:
    """(gt, pred) uint32 labels from runs of (gt label, pred label, number of points)."""
    gt = np.repeat([p[0] for p in parts], [p[2] for p in parts]).astype(np.uint32)
    pred = np.repeat([p[1] for p in parts], [p[2] for p in parts]).astype(np.uint32)
    return gt, pred


# --------------------------------------------------------------------------- class tables


def test_learning_map_matches_the_class_tables() -> None:
    assert set(LEARNING_MAP) == set(CLASS_NAMES)  # every raw class of semantic-kitti.yaml
    assert len(LEARNING_NAMES) == 20 and set(LEARNING_MAP.values()) == set(range(20))
    # The raw thing classes are exactly those whose training class is a thing class.
    assert {r for r, c in LEARNING_MAP.items() if c in LEARNING_THINGS} == set(THING_CLASSES)
    assert sorted(LEARNING_THINGS + LEARNING_STUFF) == list(range(1, 20))
    # learning_map_inv: each training class is named after its raw class.
    for raw, name in CLASS_NAMES.items():
        if not name.startswith("moving") and raw not in (1, 13, 16, 52, 60, 99):
            assert LEARNING_NAMES[LEARNING_MAP[raw]] == name
    assert learning_class(np.array([lab(MOVING_CAR, 3), lab(LANE), 999, lab(OTHER_STRUCTURE)]))[
        :4
    ].tolist() == [1, 9, 0, 0]


# --------------------------------------------------------------------------- reference example


def test_he_et_al_example() -> None:
    """semantic-kitti-api's own example; its printed results are the expected values."""
    sem_p, ins_p, sem_g, ins_g = [], [], [], []

    def add(sp, ip, sg, ig, n):
        (
            sem_p.extend([sp] * n),
            ins_p.extend([ip] * n),
            sem_g.extend([sg] * n),
            ins_g.extend([ig] * n),
        )

    add(0, 0, 0, 0, 50)  # ignore
    add(1, 0, 1, 0, 40), add(2, 0, 1, 0, 10)  # grass, 10 predicted sky
    add(2, 0, 2, 0, 40), add(1, 0, 2, 0, 10)  # sky, 10 predicted grass
    add(3, 35, 4, 22, 50)  # dog predicted as person
    add(3, 8, 3, 33, 150), add(3, 8, 3, 42, 50), add(3, 95, 3, 11, 100)  # 3 persons, 2 predicted
    a = [np.array(v, dtype=np.int64) for v in (sem_p, ins_p, sem_g, ins_g)]
    c = segment_counts(a[0], a[1] + 1, a[2], a[3] + 1, 5, (0,), min_points=1)
    s = class_scores(c)
    inc = [1, 2, 3, 4]
    assert s["pq"][inc].mean() == pytest.approx(0.47916666666666663, abs=1e-15)
    assert s["sq"][inc].mean() == pytest.approx(0.5520833333333333, abs=1e-15)
    assert s["rq"][inc].mean() == pytest.approx(0.6666666666666666, abs=1e-15)
    assert s["iou"][inc].mean() == pytest.approx(0.5476190476190476, abs=1e-15)
    np.testing.assert_allclose(s["pq"], [0, 2 / 3, 2 / 3, 0.5833333333333333, 0], atol=1e-15)
    np.testing.assert_allclose(s["sq"], [0, 2 / 3, 2 / 3, 0.875, 0], atol=1e-15)
    np.testing.assert_allclose(s["rq"], [0, 1, 1, 2 / 3, 0], atol=1e-15)
    np.testing.assert_allclose(s["iou"], [0, 2 / 3, 2 / 3, 0.8571428571428571, 0], atol=1e-15)


# --------------------------------------------------------------------------- hand-built frames


def test_tp_fp_fn_and_iou_on_a_hand_built_frame() -> None:
    gt, pred = runs(
        (lab(CAR, 1), lab(CAR, 7), 60),  # car 1: 60 points in cluster 7 ...
        (lab(ROAD), lab(CAR, 7), 10),  # ... which also holds 10 road points: IoU 60/70
        (lab(CAR, 2), lab(CAR, 8), 30),  # car 2 split in two halves of 30:
        (lab(CAR, 2), lab(CAR, 9), 30),  # IoU 1/2 each, not > 1/2 -> FN, and 2 small clusters
        (lab(CAR, 3), lab(CAR, 10), 49),  # car 3 (49 points) with a 49-point cluster of ...
        (lab(BUILDING), lab(CAR, 10), 51),  # ... building: IoU 0.49 -> cluster 10 (100) is FP
        (lab(ROAD), lab(ROAD), 200),  # road: one segment each, IoU 200/210 (10 road points
        (lab(BUILDING), lab(BUILDING), 100),  # went to car 7) ; building IoU 100/151
        (lab(CAR, 4), lab(CAR, 11), 10),  # a 10-point car found: TP although under 50
    )
    c = panoptic_counts(gt, pred)
    assert (c.tp[L_CAR], c.fp[L_CAR], c.fn[L_CAR]) == (2, 1, 1)
    assert c.iou_sum[L_CAR] == pytest.approx(60 / 70 + 1.0)
    assert (c.tp[L_ROAD], c.fp[L_ROAD], c.fn[L_ROAD]) == (1, 0, 0)
    assert c.iou_sum[L_ROAD] == pytest.approx(200 / 210)
    assert (c.tp[L_BUILDING], c.fp[L_BUILDING], c.fn[L_BUILDING]) == (1, 0, 0)
    assert c.iou_sum[L_BUILDING] == pytest.approx(100 / 151)
    # car 3 (49 points) unmatched: under 50 points, no FN; clusters 8, 9 (30 points): no FP.
    s = class_scores(c)
    assert s["sq"][L_CAR] == pytest.approx((60 / 70 + 1) / 2)
    assert s["rq"][L_CAR] == pytest.approx(2 / (2 + 0.5 + 0.5))
    assert s["pq"][L_CAR] == pytest.approx((60 / 70 + 1) / 3)
    # semantic IoU of car: 60 + 60 + 49 + 10 car points all predicted car; 10 road + 51
    # building predicted car.
    assert s["iou"][L_CAR] == pytest.approx(179 / (179 + 61))
    summary = panoptic_summary(c)
    assert summary["pq_mean"] == pytest.approx((s["pq"][L_CAR] + 200 / 210 + 100 / 151) / 19)
    assert summary["pq_things"] == pytest.approx(s["pq"][L_CAR] / 8)
    assert summary["pq_stuff"] == pytest.approx((200 / 210 + 100 / 151) / 11)
    assert summary["pq_dagger"] == pytest.approx(
        (s["pq"][L_CAR] + s["iou"][L_ROAD] + s["iou"][L_BUILDING]) / 19
    )


def test_min_points_boundary() -> None:
    for n, expected in ((49, 0), (50, 1)):
        gt, pred = runs((lab(CAR, 1), lab(CAR, 1), n), (lab(ROAD), lab(CAR, 2), n))
        # car 1 and cluster 1 match (IoU 1) ...; an unmatched n-point GT / pred segment:
        gt2, pred2 = runs((lab(CAR, 5), lab(ROAD), n), (lab(ROAD), lab(CAR, 6), n))
        c = panoptic_counts(gt2, pred2)
        assert (c.fn[L_CAR], c.fp[L_CAR]) == (expected, expected)
        c = panoptic_counts(gt, pred)
        assert (c.tp[L_CAR], c.fp[L_CAR]) == (1, expected)
    c = panoptic_counts(*runs((lab(CAR, 5), lab(ROAD), 20)), min_points=20)
    assert c.fn[L_CAR] == 1


def test_ignored_ground_truth_is_removed_everywhere() -> None:
    # 40 car points plus 60 unlabeled / other-structure points in one predicted cluster: those
    # points are removed, so the cluster is the car exactly (IoU 1), not 40/100.
    gt, pred = runs(
        (lab(CAR, 1), lab(CAR, 1), 40),
        (lab(0), lab(CAR, 1), 30),
        (lab(OTHER_STRUCTURE), lab(CAR, 1), 30),
        (lab(99), lab(CAR, 2), 80),  # a cluster on other-object only: removed, no FP
    )
    c = panoptic_counts(gt, pred)
    assert (c.tp[L_CAR], c.fp[L_CAR], c.fn[L_CAR]) == (1, 0, 0)
    assert c.iou_sum[L_CAR] == 1.0
    assert c.sem_fp[L_CAR] == 0


def test_predicted_unlabeled_points_are_in_no_segment_but_count_as_misses() -> None:
    gt, pred = runs((lab(CAR, 1), lab(CAR, 3), 60), (lab(CAR, 1), lab(0), 40))
    c = panoptic_counts(gt, pred)
    assert (c.tp[L_CAR], c.fp[L_CAR], c.fn[L_CAR]) == (1, 0, 0)
    assert c.iou_sum[L_CAR] == pytest.approx(0.6)
    assert (c.sem_tp[L_CAR], c.sem_fn[L_CAR]) == (60, 40)
    assert class_scores(c)["iou"][L_CAR] == pytest.approx(0.6)


def test_instance_zero_is_a_segment_and_full_labels_separate_segments() -> None:
    # 60 car points with instance 0 in the prediction form one segment (not "no instance"):
    gt, pred = runs((lab(ROAD), lab(CAR, 0), 60), (lab(ROAD), lab(ROAD), 100))
    c = panoptic_counts(gt, pred)
    assert c.fp[L_CAR] == 1
    # Car instance 5 and moving-car instance 5 are two segments of class car (in both):
    gt, pred = runs((lab(CAR, 5), lab(CAR, 5), 60), (lab(MOVING_CAR, 5), lab(MOVING_CAR, 5), 60))
    c = panoptic_counts(gt, pred)
    assert (c.tp[L_CAR], c.fp[L_CAR], c.fn[L_CAR]) == (2, 0, 0)
    # ... and a prediction that writes them as one segment (semantic 10) matches neither well:
    gt, pred = runs((lab(CAR, 5), lab(CAR, 5), 60), (lab(MOVING_CAR, 5), lab(CAR, 5), 60))
    c = panoptic_counts(gt, pred)
    assert (c.tp[L_CAR], c.fp[L_CAR], c.fn[L_CAR]) == (0, 1, 2)
    # lane-marking is a second road segment:
    gt, pred = runs((lab(ROAD), lab(ROAD), 100), (lab(LANE), lab(ROAD), 60))
    c = panoptic_counts(gt, pred)
    assert (c.tp[L_ROAD], c.fp[L_ROAD], c.fn[L_ROAD]) == (1, 0, 1)
    assert c.iou_sum[L_ROAD] == pytest.approx(100 / 160)


def test_wrong_class_is_fp_and_fn() -> None:
    gt, pred = runs((lab(CAR, 1), lab(PERSON, 1), 80))
    c = panoptic_counts(gt, pred)
    assert (c.tp.sum(), c.fn[L_CAR], c.fp[6]) == (0, 1, 1)


def test_empty_and_absent_classes_score_zero() -> None:
    c = panoptic_counts(np.zeros(0, np.uint32), np.zeros(0, np.uint32))
    assert c.tp.sum() == c.fp.sum() == c.fn.sum() == 0
    assert panoptic_summary(c) == {k: 0.0 for k in panoptic_summary(c)}
    pq, sq, rq = pq_sq_rq(0, 0, 0, 0.0)
    assert (pq, sq, rq) == (0.0, 0.0, 0.0)


def test_counts_pool_by_summing() -> None:
    f1 = panoptic_counts(*runs((lab(CAR, 1), lab(CAR, 1), 60)))
    f2 = panoptic_counts(*runs((lab(CAR, 1), lab(ROAD), 60), (lab(ROAD), lab(CAR, 4), 70)))
    total = PanopticCounts.total([f1, f2], 20)
    assert (total.tp[L_CAR], total.fp[L_CAR], total.fn[L_CAR]) == (1, 1, 1)
    # pooled PQ = IoU sum / (TP + FP/2 + FN/2) = 1 / 2, not the mean of the frames' 1 and 0
    assert class_scores(total)["pq"][L_CAR] == pytest.approx(0.5)
    assert PanopticCounts.total([], 20).tp.shape == (20,)


def test_bad_input() -> None:
    with pytest.raises(ValueError, match="1-D integer"):
        panoptic_counts(np.zeros(3, np.float32), np.zeros(3, np.uint32))
    with pytest.raises(ValueError, match="expected 3"):
        panoptic_counts(np.zeros(3, np.uint32), np.zeros(4, np.uint32))
    with pytest.raises(ValueError, match="0..4"):
        segment_counts(np.array([5]), np.array([1]), np.array([1]), np.array([1]), 5)


# --------------------------------------------------------------------------- brute force


def reference_counts(pc, ps, gc, gs, n_classes, min_points):
    """PanopticEval.addBatchPanoptic, class by class, segment pair by segment pair."""
    keep = gc != 0
    pc, ps, gc, gs = pc[keep], ps[keep], gc[keep], gs[keep]
    tp, fp, fn = (np.zeros(n_classes, int) for _ in range(3))
    iou_sum = np.zeros(n_classes)
    for cl in range(1, n_classes):
        pred = {s: set(np.flatnonzero((pc == cl) & (ps == s))) for s in set(ps[pc == cl])}
        gt = {s: set(np.flatnonzero((gc == cl) & (gs == s))) for s in set(gs[gc == cl])}
        mp, mg = set(), set()
        for a, pa in pred.items():
            for b, gb in gt.items():
                inter = len(pa & gb)
                if inter and inter / len(pa | gb) > 0.5:
                    tp[cl] += 1
                    iou_sum[cl] += inter / len(pa | gb)
                    mp.add(a), mg.add(b)
        fp[cl] = sum(len(v) >= min_points for k, v in pred.items() if k not in mp)
        fn[cl] = sum(len(v) >= min_points for k, v in gt.items() if k not in mg)
    return tp, fp, fn, iou_sum


@settings(max_examples=150, deadline=None)
@given(
    st.integers(1, 80).flatmap(
        lambda n: st.tuples(
            *(st.lists(st.integers(0, hi), min_size=n, max_size=n) for hi in (3, 4, 3, 4))
        )
    ),
    st.integers(1, 6),
)
def test_segment_counts_equal_brute_force(arrays, min_points) -> None:
    pc, ps, gc, gs = (np.array(a, dtype=np.int64) for a in arrays)
    c = segment_counts(pc, ps, gc, gs, 4, (0,), min_points)
    tp, fp, fn, iou_sum = reference_counts(pc, ps, gc, gs, 4, min_points)
    np.testing.assert_array_equal(c.tp, tp)
    np.testing.assert_array_equal(c.fp, fp)
    np.testing.assert_array_equal(c.fn, fn)
    np.testing.assert_allclose(c.iou_sum, iou_sum, atol=1e-12)
    assert (c.sem_tp + c.sem_fn)[1:].tolist() == np.bincount(gc[gc > 0], minlength=4)[1:].tolist()


# --------------------------------------------------------------------------- class-agnostic


def test_agnostic_counts_on_a_hand_built_frame() -> None:
    gt = np.repeat(
        np.array(
            [
                lab(CAR, 1),
                lab(BUILDING),
                lab(MOVING_CAR, 2),
                lab(PERSON, 3),
                lab(CAR),
                lab(0),
                lab(BICYCLE, 4),
            ],
            dtype=np.uint32,
        ),  # fmt: skip
        [60, 20, 70, 50, 5, 100, 55],
    )
    pred = np.repeat([1, 1, 2, 2, 3, 3, 0], [60, 20, 70, 50, 5, 100, 55])
    c = agnostic_panoptic_counts(gt, pred)
    # car 1: cluster 1 holds it and 20 building points -> IoU 60/80 (TP).
    # moving car 2 and person 3 share cluster 2: IoU 70/120 (TP) and 50/120 (person: FN).
    # cluster 3: 5 thing points with instance 0 ("other") and 100 unlabeled (removed): 5 points,
    # no FP. Bicycle 4 unclustered: FN.
    s = agnostic_scores(c)
    assert (s["tp"], s["fp"], s["fn"]) == (2, 0, 2)
    assert s["iou_sum"] == pytest.approx(60 / 80 + 70 / 120)
    assert s["pq"] == pytest.approx((60 / 80 + 70 / 120) / (2 + 0 / 2 + 2 / 2))
    assert s["sq"] == pytest.approx((60 / 80 + 70 / 120) / 2)
    assert s["rq"] == pytest.approx(2 / 3)
    # Sums over frames, and the classes are not mixed up: a person predicted as one cluster is
    # found whatever its class.
    c2 = agnostic_panoptic_counts(*runs((lab(PERSON, 9), 4, 50)))
    assert agnostic_scores(c + c2)["tp"] == 3


def test_agnostic_counts_ignore_negative_ids_and_count_large_clusters_as_fp() -> None:
    gt = np.array([lab(BUILDING)] * 60 + [lab(CAR, 1)] * 50, dtype=np.uint32)
    pred = np.array([5] * 60 + [-1] * 50)
    s = agnostic_scores(agnostic_panoptic_counts(gt, pred))
    assert (s["tp"], s["fp"], s["fn"], s["pq"]) == (0, 1, 1, 0.0)
    with pytest.raises(ValueError, match="1 class"):
        agnostic_scores(panoptic_counts(gt, gt))


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(data=st.data())
def test_fast_agnostic_counts_equal_the_definition(data) -> None:
    """agnostic_panoptic_counts (direct) equals the general segment_counts reference."""
    from flic_cli.metrics.panoptic import agnostic_panoptic_counts_reference

    n = data.draw(st.integers(1, 400))
    classes = [0, 1, 10, 30, 40, 50, 52, 252, 254]  # unlabeled, outlier, things, stuff, ignored
    sem = np.array(data.draw(st.lists(st.sampled_from(classes), min_size=n, max_size=n)))
    inst = np.array(data.draw(st.lists(st.integers(0, 4), min_size=n, max_size=n)))
    gt = ((inst << 16) | sem).astype(np.uint32)
    pred = np.array(data.draw(st.lists(st.integers(-1, 6), min_size=n, max_size=n)))
    min_points = data.draw(st.integers(1, 30))
    fast = agnostic_panoptic_counts(gt, pred, min_points)
    ref = agnostic_panoptic_counts_reference(gt, pred, min_points)
    for name in ("tp", "fp", "fn", "sem_tp", "sem_fp", "sem_fn"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(ref, name), err_msg=name)
    np.testing.assert_allclose(fast.iou_sum, ref.iou_sum, rtol=1e-12)
