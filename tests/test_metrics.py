"""Tests of the evaluation protocol (flic_cli.metrics) on hand-built frames."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import lab

from flic_cli.classes import CLASS_NAMES, GROUND_CLASSES, THING_CLASSES, ground_mask, thing_mask
from flic_cli.metrics import (
    IOU_THRESHOLDS,
    ObjectMatches,
    distance_band,
    match_objects,
    score_frame,
    segmentation_stats,
    summarize,
)

CAR, PERSON, ROAD, BUILDING, VEGETATION, MOVING_CAR = 10, 30, 40, 50, 70, 252
P_KEYS = [f"p_{x:.2f}" for x in IOU_THRESHOLDS]


def frame(*parts: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Build (gt_labels, pred) from runs of (label, cluster id, number of points)."""
    gt = np.repeat([p[0] for p in parts], [p[2] for p in parts]).astype(np.uint32)
    pred = np.repeat([p[1] for p in parts], [p[2] for p in parts]).astype(np.int64)
    return gt, pred


# --------------------------------------------------------------------------- constants


def test_constants() -> None:
    assert len(THING_CLASSES) == 18
    assert set(range(252, 260)) <= set(THING_CLASSES)
    assert GROUND_CLASSES == (40, 44, 48, 49, 60, 72)
    assert CLASS_NAMES[10] == "car" and CLASS_NAMES[259] == "moving-other-vehicle"
    assert set(CLASS_NAMES) > set(THING_CLASSES) | set(GROUND_CLASSES)
    assert len(CLASS_NAMES) == 34  # every raw class of semantic-kitti.yaml
    assert IOU_THRESHOLDS == (0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95)


def test_ground_mask_uses_semantic_bits_only() -> None:
    labels = np.array(
        [lab(ROAD), lab(ROAD, 3), lab(72), lab(CAR, 1), lab(BUILDING), 0, lab(60)], dtype=np.uint32
    )
    np.testing.assert_array_equal(
        ground_mask(labels), [True, True, True, False, False, False, True]
    )
    # objects: thing class *and* an instance id
    np.testing.assert_array_equal(
        thing_mask(labels), [False, False, False, True, False, False, False]
    )


# --------------------------------------------------------------------------- matching


def test_perfect_match() -> None:
    gt, pred = frame(
        (lab(CAR, 1), 1, 120),
        (lab(PERSON, 2), 2, 100),
        (lab(ROAD), 0, 50),
        (lab(BUILDING), 3, 40),
    )
    m = match_objects(gt, pred)
    assert len(m) == 2
    np.testing.assert_array_equal(m.instance, [1, 2])
    np.testing.assert_array_equal(m.semantic, [CAR, PERSON])
    np.testing.assert_array_equal(m.n_points, [120, 100])
    np.testing.assert_array_equal(m.cluster, [1, 2])
    np.testing.assert_array_equal(m.overlap, [120, 100])
    np.testing.assert_array_equal(m.iou, [1.0, 1.0])
    np.testing.assert_array_equal(m.n_fragments, [1, 1])
    assert np.isnan(m.distance).all()
    s = summarize(m.iou)
    assert s["objects"] == 2
    assert s["iou_mu"] == 1.0 and s["p_mu"] == 1.0
    assert all(s[k] == 1.0 for k in P_KEYS)
    assert segmentation_stats(gt, pred) == {
        "clusters": 3,
        "objects": 2,
        "over_segmented": 0,
        "under_segmented": 0,
    }


def test_object_split_into_two_clusters() -> None:
    # car of 150 points: 100 in cluster 5, 40 in cluster 6, 10 unclustered
    gt, pred = frame((lab(CAR, 1), 5, 100), (lab(CAR, 1), 6, 40), (lab(CAR, 1), 0, 10))
    m = match_objects(gt, pred)
    assert m.cluster[0] == 5
    assert m.overlap[0] == 100
    assert m.iou[0] == pytest.approx(100 / 150)
    assert m.n_fragments[0] == 2
    stats = segmentation_stats(gt, pred)
    assert stats["over_segmented"] == 1 and stats["clusters"] == 2
    assert stats["under_segmented"] == 0


def test_small_fragment_does_not_count() -> None:
    # 9 points in cluster 7 are below the 10-point fragment threshold
    gt, pred = frame((lab(CAR, 1), 5, 120), (lab(CAR, 1), 7, 9))
    m = match_objects(gt, pred)
    assert m.n_fragments[0] == 1
    assert m.iou[0] == pytest.approx(120 / 129)
    assert segmentation_stats(gt, pred)["over_segmented"] == 0


def test_merged_objects_one_cluster_one_object() -> None:
    # cars A (200 pts) and B (100 pts) fully in cluster 3 -> |cluster| = 300
    gt, pred = frame((lab(CAR, 1), 3, 200), (lab(CAR, 2), 3, 100))
    m = match_objects(gt, pred)
    np.testing.assert_array_equal(m.cluster, [3, -1])
    np.testing.assert_array_equal(m.overlap, [200, 0])
    assert m.iou[0] == pytest.approx(200 / 300)  # B would have 100 / 300, A keeps the cluster
    assert m.iou[1] == 0.0
    stats = segmentation_stats(gt, pred)
    assert stats["under_segmented"] == 1 and stats["over_segmented"] == 0

    s = summarize(m.iou)
    assert s["iou_mu"] == pytest.approx((200 / 300 + 0) / 2)
    # 2/3 = 0.667 >= 0.50, 0.55, 0.60, 0.65; < 0.70 ... 0.95; B counts nowhere
    expected = {0.5: 0.5, 0.55: 0.5, 0.6: 0.5, 0.65: 0.5}
    for x, key in zip(IOU_THRESHOLDS, P_KEYS, strict=True):
        assert s[key] == expected.get(x, 0.0), key
    assert s["p_mu"] == pytest.approx(4 * 0.5 / 10)


def test_loser_does_not_fall_back_to_second_cluster() -> None:
    # A: 200 in cluster 3; B: 60 in cluster 3, 40 in cluster 4; |cluster 3| = 260
    gt, pred = frame((lab(CAR, 1), 3, 200), (lab(CAR, 2), 3, 60), (lab(CAR, 2), 4, 40))
    m = match_objects(gt, pred)
    assert m.iou[0] == pytest.approx(200 / 260)
    # B's best overlap is cluster 3 (IoU 60 / (100 + 260 - 60)); A wins it, B is not found
    np.testing.assert_array_equal(m.cluster, [3, -1])
    assert m.iou[1] == 0.0
    np.testing.assert_array_equal(m.n_fragments, [1, 2])
    assert segmentation_stats(gt, pred) == {
        "clusters": 2,
        "objects": 2,
        "over_segmented": 1,
        "under_segmented": 1,
    }


def test_best_cluster_tie_prefers_smaller_cluster() -> None:
    # A (300 pts): 150 in cluster 1, 150 in cluster 2 -- equal overlaps; B (100 pts): 50 in
    # cluster 2, 50 unclustered. |cluster 1| = 150, |cluster 2| = 200: A takes the smaller one
    gt, pred = frame(
        (lab(CAR, 1), 1, 150),
        (lab(CAR, 1), 2, 150),
        (lab(PERSON, 2), 2, 50),
        (lab(PERSON, 2), 0, 50),
    )
    m = match_objects(gt, pred)
    np.testing.assert_array_equal(m.cluster, [1, 2])
    assert m.iou[0] == pytest.approx(150 / (300 + 150 - 150))
    assert m.iou[1] == pytest.approx(50 / (100 + 200 - 50))


def test_cluster_conflict_goes_to_higher_iou_not_larger_overlap() -> None:
    # A (300 pts): 150 in cluster 1, 150 unclustered; B (100 pts): all in cluster 1 (size 250)
    gt, pred = frame((lab(CAR, 1), 1, 150), (lab(CAR, 1), 0, 150), (lab(CAR, 2), 1, 100))
    m = match_objects(gt, pred)
    # IoU A = 150 / (300 + 250 - 150) = 0.375 < IoU B = 100 / (100 + 250 - 100) = 0.4
    np.testing.assert_array_equal(m.cluster, [-1, 1])
    np.testing.assert_array_equal(m.iou, [0.0, 100 / 250])


def test_conflict_tie_goes_to_lower_instance_id() -> None:
    # two 100-point objects in one 200-point cluster: equal IoU 100 / 200 and equal overlap
    gt, pred = frame((lab(CAR, 2), 4, 100), (lab(PERSON, 1), 4, 100))
    m = match_objects(gt, pred)
    np.testing.assert_array_equal(m.instance, [1, 2])
    np.testing.assert_array_equal(m.cluster, [4, -1])
    np.testing.assert_array_equal(m.iou, [100 / 200, 0.0])


def test_objects_below_min_points_are_ignored() -> None:
    gt, pred = frame((lab(CAR, 1), 1, 99), (lab(CAR, 2), 1, 100))
    m = match_objects(gt, pred)
    assert len(m) == 1 and m.instance[0] == 2
    # the ignored car's 99 points are still part of cluster 1: IoU = 100 / 199
    assert m.iou[0] == pytest.approx(100 / 199)
    assert summarize(m.iou)["objects"] == 1
    assert segmentation_stats(gt, pred)["objects"] == 1
    assert len(match_objects(gt, pred, min_points=99)) == 2
    empty = match_objects(frame((lab(CAR, 1), 1, 99))[0], frame((lab(CAR, 1), 1, 99))[1])
    assert len(empty) == 0
    assert empty.iou.dtype == np.float64


def test_unclustered_points_are_missed_and_background_lowers_iou() -> None:
    # car of 100: 80 in cluster 1, 20 unclustered; cluster 1 also holds 30 vegetation points
    gt, pred = frame((lab(CAR, 1), 1, 80), (lab(CAR, 1), 0, 20), (lab(VEGETATION), 1, 30))
    m = match_objects(gt, pred)
    assert m.overlap[0] == 80
    assert m.iou[0] == pytest.approx(80 / (100 + 110 - 80))  # = 80 / 130


def test_negative_cluster_ids_are_unclustered() -> None:
    gt, pred = frame((lab(CAR, 1), 1, 80), (lab(CAR, 1), -1, 20), (lab(ROAD), -1, 30))
    m = match_objects(gt, pred)
    assert m.iou[0] == pytest.approx(80 / 100)
    assert segmentation_stats(gt, pred)["clusters"] == 1


def test_object_without_any_cluster() -> None:
    gt, pred = frame((lab(CAR, 1), 0, 150), (lab(ROAD), 1, 50))
    m = match_objects(gt, pred)
    np.testing.assert_array_equal(m.cluster, [-1])
    np.testing.assert_array_equal(m.iou, [0.0])
    np.testing.assert_array_equal(m.n_fragments, [0])


def test_stuff_classes_with_instance_ids_are_ignored() -> None:
    gt, pred = frame(
        (lab(BUILDING, 7), 1, 200),
        (lab(ROAD, 3), 2, 300),
        (lab(0, 5), 3, 150),
        (lab(CAR), 4, 150),  # thing class without instance id
    )
    m = match_objects(gt, pred)
    assert len(m) == 0
    assert summarize(m.iou)["objects"] == 0


def test_same_instance_id_different_classes_are_different_objects() -> None:
    gt, pred = frame((lab(CAR, 1), 1, 100), (lab(MOVING_CAR, 1), 2, 100))
    m = match_objects(gt, pred)
    np.testing.assert_array_equal(m.semantic, [CAR, MOVING_CAR])
    np.testing.assert_array_equal(m.iou, [1.0, 1.0])


def test_distance_is_centroid_range() -> None:
    gt, pred = frame((lab(CAR, 1), 1, 100), (lab(ROAD), 0, 10))
    points = np.zeros((110, 3), dtype=np.float32)
    points[:50] = (10.0, 0.0, 0.0)
    points[50:100] = (0.0, 20.0, -1.0)
    points[100:] = (500.0, 500.0, 500.0)  # not part of the object
    m = match_objects(gt, pred, points=points)
    # centroid (5, 10, -0.5)
    assert m.distance[0] == pytest.approx(np.sqrt(5.0**2 + 10.0**2 + 0.5**2))


def test_as_dict_builds_a_dataframe() -> None:
    gt, pred = frame((lab(CAR, 1), 1, 100), (lab(PERSON, 2), 0, 100))
    df = pd.DataFrame(match_objects(gt, pred).as_dict())
    assert list(df.columns) == [
        "label",
        "semantic",
        "instance",
        "n_points",
        "distance",
        "cluster",
        "overlap",
        "iou",
        "n_fragments",
    ]
    assert len(df) == 2
    assert df["iou"].tolist() == [1.0, 0.0]


def test_bad_inputs_raise() -> None:
    gt, pred = frame((lab(CAR, 1), 1, 100))
    with pytest.raises(ValueError):
        match_objects(gt, pred[:-1])
    with pytest.raises(ValueError):
        match_objects(gt, pred.astype(np.float64))
    with pytest.raises(ValueError):
        match_objects(gt, pred, points=np.zeros((99, 3)))


def test_sparse_paths_for_large_ids() -> None:
    # huge cluster ids take the np.unique path instead of bincount; results must not change
    gt, pred = frame((lab(CAR, 1), 5, 100), (lab(CAR, 1), 6, 40), (lab(CAR, 2), 6, 120))
    big = np.where(pred > 0, pred * 10**12, 0)
    a, b = match_objects(gt, pred), match_objects(gt, big)
    np.testing.assert_array_equal(a.iou, b.iou)
    np.testing.assert_array_equal(np.where(a.cluster > 0, a.cluster * 10**12, -1), b.cluster)
    assert segmentation_stats(gt, pred) == segmentation_stats(gt, big)


# --------------------------------------------------------------------------- pooled scores


def test_iou_mu_pools_objects_not_frames() -> None:
    # frame 1: one perfect object; frame 2: three objects of IoU 50 / 100 each
    gt1, pred1 = frame((lab(CAR, 1), 1, 100))
    gt2, pred2 = frame(
        (lab(CAR, 1), 1, 50), (lab(CAR, 1), 0, 50),
        (lab(CAR, 2), 2, 50), (lab(CAR, 2), 0, 50),
        (lab(CAR, 3), 3, 50), (lab(CAR, 3), 0, 50),
    )  # fmt: skip
    ious = np.concatenate([match_objects(gt1, pred1).iou, match_objects(gt2, pred2).iou])
    s = summarize(ious)
    assert s["objects"] == 4
    assert s["iou_mu"] == pytest.approx((1.0 + 3 * 0.5) / 4)  # 0.625, not (1.0 + 0.5) / 2
    assert s["p_0.50"] == 1.0
    assert s["p_0.55"] == pytest.approx(1 / 4)
    assert s["p_mu"] == pytest.approx((1.0 + 9 * 0.25) / 10)


def test_p_threshold_boundary_is_inclusive() -> None:
    # 225 of 300 points in an otherwise clean cluster: IoU exactly 225 / 300 = 0.75
    gt, pred = frame((lab(CAR, 1), 1, 225), (lab(CAR, 1), 0, 75))
    m = match_objects(gt, pred)
    assert m.iou[0] == 0.75
    s = summarize(m.iou)
    assert s["p_0.75"] == 1.0 and s["p_0.80"] == 0.0
    assert s["p_mu"] == pytest.approx(6 / 10)
    # floating round-off just below a threshold still counts (0.1 * 7 vs 0.7, 0.55 from sums)
    s = summarize(np.array([0.7 - 1e-15, 0.1 + 0.45]))
    assert s["p_0.70"] == pytest.approx(1 / 2) and s["p_0.55"] == 1.0


def test_summarize_empty() -> None:
    s = summarize(np.zeros(0))
    assert s["objects"] == 0
    assert np.isnan(s["iou_mu"]) and np.isnan(s["p_mu"])
    assert all(np.isnan(s[k]) for k in P_KEYS)


def test_distance_band() -> None:
    d = np.array([0.0, 19.99, 20.0, 39.9, 40.0, 120.0, np.nan])
    np.testing.assert_array_equal(
        distance_band(d), ["0-20", "0-20", "20-40", "20-40", ">40", ">40", "n/a"]
    )


# --------------------------------------------------------------------------- properties

LABEL_PALETTE = [
    0,
    lab(ROAD),
    lab(BUILDING, 3),
    lab(CAR, 1),
    lab(CAR, 2),
    lab(PERSON, 1),
    lab(MOVING_CAR, 2),
    lab(CAR),
]


def reference_match(
    gt: np.ndarray, pred: np.ndarray, min_points: int, min_frag: int
) -> dict[int, tuple[int, Fraction, int]]:
    """Loop implementation of the protocol: label -> (cluster, exact IoU, fragments)."""
    thing = [int(v) for v in gt if (int(v) & 0xFFFF) in THING_CLASSES and int(v) >> 16 > 0]
    objects = sorted(v for v in set(thing) if thing.count(v) >= min_points)
    clusters = sorted({int(c) for c in pred if c > 0})
    size = {c: int(np.sum(pred == c)) for c in clusters}
    picks: dict[int, tuple[int, Fraction, int]] = {}
    frags: dict[int, int] = {}
    for o in objects:
        in_o = gt == o
        n = int(in_o.sum())
        cands = []
        for c in clusters:
            ov = int(np.sum(in_o & (pred == c)))
            if ov > 0:
                cands.append((-ov, size[c], c, Fraction(ov, n + size[c] - ov)))
        frags[o] = sum(1 for cand in cands if -cand[0] >= min_frag)
        if cands:
            neg_ov, _, c, iou = min(cands)
            picks[o] = (c, iou, -neg_ov)
    result = {o: (-1, Fraction(0), frags[o]) for o in objects}
    for c in clusters:
        takers = [o for o in picks if picks[o][0] == c]
        if takers:
            winner = max(takers, key=lambda o: (picks[o][1], picks[o][2], -o))
            result[winner] = (c, picks[winner][1], frags[winner])
    return result


frames = st.integers(min_value=1, max_value=80).flatmap(
    lambda n: st.tuples(
        st.lists(st.sampled_from(LABEL_PALETTE), min_size=n, max_size=n),
        st.lists(st.integers(min_value=-1, max_value=6), min_size=n, max_size=n),
        st.integers(min_value=1, max_value=6),
        st.integers(min_value=1, max_value=4),
    )
)


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(frames)
def test_matches_loop_reference(case: tuple[list[int], list[int], int, int]) -> None:
    labels, clusters, min_points, min_frag = case
    gt = np.array(labels, dtype=np.uint32)
    pred = np.array(clusters, dtype=np.int64)
    m = match_objects(gt, pred, min_points=min_points, min_fragment_points=min_frag)
    ref = reference_match(gt, pred, min_points, min_frag)

    assert m.label.tolist() == sorted(ref)
    assert np.all((m.iou >= 0.0) & (m.iou <= 1.0))
    matched = m.cluster[m.cluster >= 0]
    assert len(set(matched.tolist())) == matched.size  # one cluster, one object
    assert np.array_equal(m.cluster == -1, m.iou == 0.0)
    for i, label in enumerate(m.label.tolist()):
        c, iou, frags = ref[label]
        assert m.cluster[i] == c
        assert m.iou[i] == float(iou)
        assert m.n_fragments[i] == frags

    stats = segmentation_stats(gt, pred, min_points=min_points, min_fragment_points=min_frag)
    assert stats["objects"] == len(m)
    assert stats["over_segmented"] == int(np.sum(m.n_fragments >= 2))
    assert stats["clusters"] == len(set(pred[pred > 0].tolist()))


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(frames, st.data())
def test_perfect_segmentation_scores_one(
    case: tuple[list[int], list[int], int, int], data: st.DataObject
) -> None:
    labels, _, min_points, _ = case
    gt = np.array(labels, dtype=np.uint32)
    thing = np.isin(gt & 0xFFFF, THING_CLASSES) & (gt >> 16 > 0)
    _, inverse = np.unique(gt, return_inverse=True)
    # every GT object its own cluster id; other points unclustered or in clusters of their own
    others = data.draw(st.sampled_from(["unclustered", "background-clusters"]))
    pred = np.where(thing, inverse + 1, 0 if others == "unclustered" else 1000 + inverse)
    m = match_objects(gt, pred, min_points=min_points)
    np.testing.assert_array_equal(m.iou, np.ones(len(m)))
    np.testing.assert_array_equal(m.overlap, m.n_points)
    s = summarize(m.iou)
    if len(m):
        assert s["iou_mu"] == 1.0 and s["p_mu"] == 1.0


def test_object_matches_is_frozen() -> None:
    m = match_objects(*frame((lab(CAR, 1), 1, 100)))
    assert isinstance(m, ObjectMatches)
    with pytest.raises(AttributeError):
        m.iou = np.zeros(1)  # type: ignore[misc]


def reference_under_segmented(
    gt: np.ndarray, pred: np.ndarray, objects: list[int], frag: int
) -> int:
    """Loop count of clusters holding at least ``frag`` points of each of two or more objects."""
    clusters = sorted({int(c) for c in pred if c > 0})
    return sum(
        1
        for c in clusters
        if sum(1 for o in objects if np.sum((gt == o) & (pred == c)) >= frag) >= 2
    )


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(frames, st.sampled_from(["int64", "int32", "uint16", "bool", "big", "negative"]), st.data())
def test_score_frame_equals_the_loop_reference(
    case: tuple[list[int], list[int], int, int], ids: str, data: st.DataObject
) -> None:
    labels, clusters, min_points, min_frag = case
    gt = np.array(labels, dtype=np.uint32)
    pred = np.array(clusters, dtype=np.int64)
    if ids == "big":  # ids far apart: renumbered before counting
        pred = np.where(pred > 0, pred * 10**12 + 7, pred)
    elif ids == "negative":
        pred = np.where(pred > 0, pred, -(10**9))
    elif ids in ("uint16", "bool"):
        pred = np.maximum(pred, 0).astype(ids)
    else:
        pred = pred.astype(ids)
    seed = data.draw(st.integers(0, 2**32 - 1))
    points = np.random.default_rng(seed).normal(0, 30, (gt.size, 3)).astype(np.float32)

    m, stats = score_frame(gt, pred, points, min_points=min_points, min_fragment_points=min_frag)
    pred64 = pred.astype(np.int64)
    ref = reference_match(gt, pred64, min_points, min_frag)
    objects = sorted(ref)
    assert m.label.tolist() == objects and m.label.dtype == np.uint32
    assert m.semantic.tolist() == [o & 0xFFFF for o in objects]
    assert m.instance.tolist() == [o >> 16 for o in objects]
    for i, o in enumerate(objects):
        c, iou, frags = ref[o]
        in_o = gt == o
        assert m.n_points[i] == in_o.sum()
        assert m.cluster[i] == c and m.iou[i] == float(iou) and m.n_fragments[i] == frags
        assert m.overlap[i] == (np.sum(in_o & (pred64 == c)) if c >= 0 else 0)
        centroid = points[in_o].astype(np.float64).mean(axis=0)
        assert m.distance[i] == pytest.approx(np.linalg.norm(centroid), rel=1e-12, abs=1e-12)
    for field in ("semantic", "instance", "n_points", "cluster", "overlap", "n_fragments"):
        assert getattr(m, field).dtype == np.int64
    assert stats == {
        "clusters": len({int(c) for c in pred64 if c > 0}),
        "objects": len(objects),
        "over_segmented": sum(1 for o in objects if ref[o][2] >= 2),
        "under_segmented": reference_under_segmented(gt, pred64, objects, min_frag),
    }
    # the two public functions give the same as score_frame
    alone = match_objects(gt, pred, points, min_points=min_points, min_fragment_points=min_frag)
    for a, b in zip(alone.as_dict().values(), m.as_dict().values(), strict=True):
        np.testing.assert_array_equal(a, b)
    assert segmentation_stats(gt, pred, min_points, min_frag) == stats
    assert np.isnan(match_objects(gt, pred, min_points=min_points).distance).all()


def test_score_frame_on_an_empty_frame() -> None:
    m, stats = score_frame(np.zeros(0, dtype=np.uint32), np.zeros(0, dtype=np.int64))
    assert len(m) == 0
    assert stats == {"clusters": 0, "objects": 0, "over_segmented": 0, "under_segmented": 0}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_score_frame_with_hundreds_of_objects(seed: int) -> None:
    # more distinct object labels than the first hash table holds (it grows), in shuffled order
    rng = np.random.default_rng(seed)
    n = 4000
    classes, instances = rng.choice(THING_CLASSES, 300), rng.integers(1, 1 << 16, 300)
    objects = [lab(int(c), int(i)) for c, i in zip(classes, instances, strict=True)]
    gt = np.array(objects + [lab(ROAD)] * 50, dtype=np.uint32)[rng.integers(0, 350, n)]
    pred = rng.integers(-1, 60, n)
    m, stats = score_frame(gt, pred, min_points=5, min_fragment_points=2)
    ref = reference_match(gt, pred, 5, 2)
    assert m.label.tolist() == sorted(ref) and len(ref) > 200
    for i, o in enumerate(m.label.tolist()):
        cluster, iou, fragments = ref[o]
        assert (m.cluster[i], m.iou[i], m.n_fragments[i]) == (cluster, float(iou), fragments)
    assert stats["objects"] == len(ref)
    assert stats["under_segmented"] == reference_under_segmented(gt, pred, sorted(ref), 2)
