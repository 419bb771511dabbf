"""Tests of flic_cli.labels: the SemanticKITTI label encoding, checked against arithmetic."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flic_cli.labels import MAX_ID, N_IDS, encode, has_instance, instance, semantic

ids = st.integers(0, 65535)


@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(ids, ids), min_size=1, max_size=40))
def test_encode_is_instance_times_65536_plus_semantic(pairs: list[tuple[int, int]]) -> None:
    sem = np.array([p[0] for p in pairs])
    ins = np.array([p[1] for p in pairs])
    labels = encode(sem, ins)
    assert labels.dtype == np.uint32
    assert labels.tolist() == [i * 65536 + s for s, i in pairs]
    np.testing.assert_array_equal(semantic(labels), sem)
    np.testing.assert_array_equal(instance(labels), ins)
    np.testing.assert_array_equal(has_instance(labels), ins > 0)


def test_any_integer_dtype_is_read_as_uint32() -> None:
    raw = np.array([0, 40, 3 * 65536 + 10, 2**32 - 1], dtype=np.int64)
    assert semantic(raw).tolist() == [0, 40, 10, 65535]
    assert instance(raw).tolist() == [0, 0, 3, 65535]
    assert has_instance(raw).tolist() == [False, False, True, True]


def test_constants() -> None:
    assert MAX_ID == 65535 and N_IDS == 65536


@pytest.mark.parametrize(
    ("sem", "ins", "name"), [([65536], [0], "semantic"), ([0], [-1], "instance")]
)
def test_ids_beyond_16_bits_are_errors(sem: list[int], ins: list[int], name: str) -> None:
    with pytest.raises(ValueError, match=f"{name} ids must lie in 0..65535"):
        encode(np.array(sem), np.array(ins))
