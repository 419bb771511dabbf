"""Tests of flic_cli.semantics and of predictions with semantics (flic_cli.io.semantickitti).

How semantic-kitti-api counts the written labels is replicated with
:func:`flic_cli.metrics.panoptic.panoptic_counts` (cross-checked against its ``PanopticEval``).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import lab

from flic_cli.classes import THING_CLASSES
from flic_cli.errors import FlicInputError
from flic_cli.io import read_predictions, write_label, write_predictions
from flic_cli.io.semantickitti import read_semantics, semantics_path, write_semantic_predictions
from flic_cli.metrics.panoptic import class_scores, panoptic_counts
from flic_cli.semantics import MODES, cluster_mask, combine, oracle_semantics

CAR, PERSON, ROAD, BUILDING, MOVING_CAR = 10, 30, 40, 50, 252
L_CAR = 1


def test_modes_and_oracle() -> None:
    assert MODES == ("none", "oracle")
    gt = np.array([lab(CAR, 3), lab(ROAD), lab(MOVING_CAR, 9), 0], dtype=np.uint32)
    np.testing.assert_array_equal(oracle_semantics(gt), [CAR, ROAD, MOVING_CAR, 0])
    assert oracle_semantics(gt).dtype == np.uint16
    np.testing.assert_array_equal(cluster_mask(oracle_semantics(gt)), [True, False, True, False])
    assert cluster_mask(np.array(THING_CLASSES)).all()


def test_combine_rules() -> None:
    sem = np.array([CAR, CAR, CAR, CAR, ROAD, ROAD, PERSON, MOVING_CAR, BUILDING, 0])
    ids = np.array([2, 2, 0, 0, 2, 0, 0, -1, 5, 7])
    labels = combine(sem, ids)
    assert labels.dtype == np.uint32
    np.testing.assert_array_equal(labels & 0xFFFF, sem)  # semantics untouched
    inst = labels >> 16
    # thing points in a cluster keep its id; stuff and class-0 points get 0 whatever their id
    assert inst[:2].tolist() == [2, 2] and inst[4:6].tolist() == [0, 0]
    assert inst[8:].tolist() == [0, 0]
    # unclustered thing points: one id each, above the largest cluster id (2), in scan order
    # across all classes (a person and a moving-car point never share an instance id)
    assert inst[2:4].tolist() == [3, 4]
    assert inst[6] == 5 and inst[7] == 6


def test_unclustered_thing_points_are_never_counted_as_instances() -> None:
    """The rule against what PanopticEval counts: 300 unclustered car points add no FP."""
    n = 300
    gt = np.array([lab(ROAD)] * 100 + [lab(CAR, 1)] * 80 + [lab(CAR, 2)] * n, dtype=np.uint32)
    sem = oracle_semantics(gt)
    ids = np.r_[np.zeros(100), np.ones(80), np.zeros(n)].astype(int)  # car 2 not clustered
    c = panoptic_counts(gt, combine(sem, ids))
    assert (c.tp[L_CAR], c.fp[L_CAR], c.fn[L_CAR]) == (1, 0, 1)  # car 2 missed, nothing else
    # Writing instance 0 for them instead makes one car segment of all of them, counted as an
    # instance: here a TP (it is car 2) ...
    naive = ((ids.astype(np.uint32) << 16) | sem).astype(np.uint32)
    assert panoptic_counts(gt, naive).tp[L_CAR] == 2
    # ... and, with three small cars left unclustered, a 90-point FP (IoU 1/3 with each).
    small = np.array([lab(ROAD)] * 100 + [lab(CAR, k) for k in (7, 8, 9) for _ in range(30)])
    small = small.astype(np.uint32)
    naive = oracle_semantics(small).astype(np.uint32)
    assert panoptic_counts(small, naive).fp[L_CAR] == 1
    ours = combine(oracle_semantics(small), np.zeros(small.size, int))
    assert panoptic_counts(small, ours).fp[L_CAR] == 0
    # The semantic IoU does not depend on the instance ids: same as with instance 0.
    s_ours = class_scores(panoptic_counts(gt, combine(sem, ids)))["iou"]
    s_sem = class_scores(panoptic_counts(gt, sem.astype(np.uint32)))["iou"]
    np.testing.assert_array_equal(s_ours, s_sem)


def test_one_point_object_is_the_only_tp_an_unclustered_point_can_make() -> None:
    gt = np.array([lab(CAR, 1)] + [lab(CAR, 2)] * 2 + [lab(ROAD)] * 60, dtype=np.uint32)
    c = panoptic_counts(gt, combine(oracle_semantics(gt), np.zeros(gt.size, int)))
    assert (c.tp[L_CAR], c.fp[L_CAR], c.fn[L_CAR], c.iou_sum[L_CAR]) == (1, 0, 0, 1.0)


def test_ids_cycle_when_they_run_out() -> None:
    n_loose = 300
    sem = np.full(n_loose + 2, CAR)
    ids = np.r_[65400, 65400, np.zeros(n_loose, int)]  # 135 free ids for 300 points
    inst = combine(sem, ids) >> 16
    loose = inst[2:]
    assert loose.min() == 65401 and loose.max() == 65535
    assert np.bincount(loose).max() == 3  # ceil(300 / 135): segments far under 50 points
    gt = np.array([lab(ROAD)] * (n_loose + 2), dtype=np.uint32)
    assert panoptic_counts(gt, combine(sem, ids)).fp[L_CAR] == 0


def test_combine_errors() -> None:
    with pytest.raises(ValueError, match="one length"):
        combine(np.zeros(3, int), np.zeros(4, int))
    with pytest.raises(ValueError, match="0..65535"):
        combine(np.array([CAR]), np.array([70000]))
    with pytest.raises(ValueError, match="under 50 points"):
        combine(np.full(3, CAR), np.array([65535, 0, 0]))
    with pytest.raises(ValueError, match="under 50 points"):
        combine(np.full(50 * 10 + 1, CAR), np.r_[65525, np.zeros(500, int)])


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(st.sampled_from([0, CAR, PERSON, ROAD, MOVING_CAR]), st.integers(0, 4))),
)
def test_combine_keeps_semantics_and_clusters_and_isolates_loose_points(pairs) -> None:
    sem = np.array([p[0] for p in pairs], dtype=np.int64)
    ids = np.array([p[1] for p in pairs], dtype=np.int64)
    labels = combine(sem, ids)
    np.testing.assert_array_equal(labels & 0xFFFF, sem)
    inst = (labels >> 16).astype(np.int64)
    thing = np.isin(sem, THING_CLASSES)
    np.testing.assert_array_equal(inst[thing & (ids > 0)], ids[thing & (ids > 0)])
    assert (inst[~thing] == 0).all()
    loose = thing & (ids == 0)
    # every loose point is alone in its full label value, and none reuses a cluster's label
    values, counts = np.unique(labels, return_counts=True)
    alone = set(values[counts == 1].tolist())
    assert all(int(v) in alone for v in labels[loose])
    assert (inst[loose] > ids[thing].max(initial=0)).all()


# --------------------------------------------------------------------------- files


def test_predictions_round_trip_with_and_without_semantics(tmp_path) -> None:
    ids = np.array([0, 1, 65535, 7, 0], dtype=np.int64)
    sem = np.array([40, 10, 252, 30, 0])
    write_predictions(tmp_path, "08", 3, ids)  # default: as before, semantic 0
    np.testing.assert_array_equal(read_predictions(tmp_path, "08", 3), ids)
    got_ids, got_sem = read_predictions(tmp_path, "08", 3, n_points=5, semantics=True)
    np.testing.assert_array_equal(got_ids, ids)
    assert (got_sem == 0).all() and got_sem.dtype == np.int32
    raw = np.fromfile(tmp_path / "sequences/08/predictions/000003.label", dtype="<u4")
    np.testing.assert_array_equal(raw, ids << 16)

    path = write_predictions(tmp_path, "08", 3, ids, sem)
    got_ids, got_sem = read_predictions(tmp_path, "08", 3, semantics=True)
    np.testing.assert_array_equal(got_ids, ids)
    np.testing.assert_array_equal(got_sem, sem)
    np.testing.assert_array_equal(np.fromfile(path, dtype="<u4"), (ids << 16) | sem)
    with pytest.raises(ValueError, match="shape"):
        write_predictions(tmp_path, "08", 3, ids, sem[:2])
    with pytest.raises(ValueError, match="65535"):
        write_predictions(tmp_path, "08", 3, ids, sem + 70000)


def test_write_semantic_predictions_round_trip(tmp_path) -> None:
    sem = np.array([CAR, CAR, ROAD, PERSON, PERSON])
    ids = np.array([4, 0, 4, 0, 0])
    path = write_semantic_predictions(tmp_path, "00", 12, sem, ids)
    assert path == tmp_path / "sequences/00/predictions/000012.label"
    labels = np.fromfile(path, dtype="<u4")
    np.testing.assert_array_equal(labels, combine(sem, ids))
    got_ids, got_sem = read_predictions(tmp_path, "00", 12, semantics=True)
    np.testing.assert_array_equal(got_sem, sem)
    np.testing.assert_array_equal(got_ids, [4, 5, 0, 6, 7])  # one id per loose point


def test_read_semantics(tmp_path) -> None:
    labels = np.array([lab(CAR, 3), lab(ROAD), lab(MOVING_CAR, 1)], dtype=np.uint32)
    write_label(semantics_path(tmp_path, "08", 7), labels)
    assert semantics_path(tmp_path, "08", 7) == tmp_path / "sequences/08/predictions/000007.label"
    sem = read_semantics(tmp_path, "08", 7, 3)
    np.testing.assert_array_equal(sem, [CAR, ROAD, MOVING_CAR])  # upper bits ignored
    assert sem.dtype == np.uint16
    with pytest.raises(FlicInputError, match="holds 3 labels but the scan has 4"):
        read_semantics(tmp_path, "08", 7, 4)
    with pytest.raises(FlicInputError, match="does not exist"):
        read_semantics(tmp_path, "08", 8, 3)
    write_label(semantics_path(tmp_path, "08", 9), np.array([10, 5, 400, 10], dtype=np.uint32))
    with pytest.raises(FlicInputError, match="does not define: 5, 400"):
        read_semantics(tmp_path, "08", 9, 4)
