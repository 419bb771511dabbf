"""Point-based removers: the per-pixel decision comes from the point that owns the pixel."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flic_cli.errors import FlicInputError
from flic_cli.ground import REMOVERS, pixel_mask, pixel_owners
from flic_cli.projection import project_points


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(-1, 11), st.floats(0.5, 50.0, allow_nan=False)),
        min_size=0,
        max_size=40,
    )
)
def test_pixel_owner_is_the_nearest_point_of_the_pixel(items):
    from flic_cli.range_image import RangeImage

    pix = np.array([p for p, _ in items], dtype=np.int64)
    rng = np.array([d for _, d in items], dtype=np.float64)
    points = np.zeros((len(items), 3))
    points[:, 0] = rng  # a point's range is its x here
    image = RangeImage(np.zeros((3, 4), np.float32), np.zeros(3), pix, "spherical")
    owner = pixel_owners(image, points)
    for p in range(12):
        members = [i for i in range(len(items)) if pix[i] == p]
        if not members:
            assert owner[p] == -1
        else:  # the nearest; ties go to the first
            best = min(members, key=lambda i: (rng[i], i))
            assert owner[p] == best


def test_pixel_mask_follows_the_owner_on_a_projected_scan():
    rng = np.random.default_rng(3)
    pts = rng.uniform(-20, 20, size=(3000, 3)).astype(np.float32)
    pts[:, 2] = rng.uniform(-2, 1, 3000)
    image = project_points(pts, width=64, mode="spherical", rows=8, fov_up_deg=10, fov_down_deg=-30)
    decision = rng.random(3000) < 0.5
    mask = pixel_mask(image, pts, decision)
    owner = pixel_owners(image, pts)
    valid = image.ranges.reshape(-1) > 0
    assert np.array_equal(owner >= 0, valid)  # exactly the pixels with a range have an owner
    # the owner's range is the pixel's range
    d = np.linalg.norm(pts.astype(np.float64), axis=1).astype(np.float32)
    assert np.array_equal(d[owner[valid]], image.ranges.reshape(-1)[valid])
    assert np.array_equal(mask.reshape(-1)[valid], decision[owner[valid]])
    assert not mask.reshape(-1)[~valid].any()


def test_patchworkpp_removes_a_flat_road_and_keeps_a_box(small_sample):
    pytest.importorskip("pypatchworkpp")
    from flic_cli.io import open_dataset

    ds = open_dataset(small_sample.kitti_root)
    frame = ds.load(ds.refs()[0])
    image = project_points(frame.points)
    ground = REMOVERS["patchworkpp"]().extract(image, frame.points).mask
    assert ground.shape == image.ranges.shape
    assert not ground[image.ranges == 0].any()
    on = ground.reshape(-1)[image.point_pixel]
    sem = frame.labels & 0xFFFF
    assert on[sem == 40].mean() > 0.9  # road
    assert on[np.isin(sem, [10, 252])].mean() < 0.1  # cars


@pytest.fixture
def without_optional_packages(monkeypatch):
    """Python as a plain ``pip install flic`` leaves it: no pypatchworkpp, no dbscan."""
    import builtins
    import importlib.util

    missing = {"pypatchworkpp", "dbscan"}
    real_import = builtins.__import__
    real_find_spec = importlib.util.find_spec

    def no_import(name, *args, **kwargs):
        if name.split(".")[0] in missing:
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    def no_spec(name, *args, **kwargs):
        return None if name.split(".")[0] in missing else real_find_spec(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_import)
    monkeypatch.setattr(importlib.util, "find_spec", no_spec)


def test_without_the_extras_the_shipped_config_loads_and_other_removers_build(
    without_optional_packages,
):
    # The shipped config names every remover and the fastdbscan preset; a plain install (no
    # extras) must still load it and run everything that does not need them.
    from flic_cli.config import load_config
    from flic_cli.runs.pipeline import build_segmenter

    config = load_config()
    for remover in ("paper", "column", "bogoslavskyi"):
        seg = build_segmenter(config, "flic14", "ground", remover)
        assert seg.ground_name == remover
    assert build_segmenter(config, "dbscan", "ground", "column").method.backend == "sklearn"


@pytest.mark.parametrize(
    ("method", "remover", "hint"),
    [("flic0", "patchworkpp", "flic[patchworkpp]"), ("dbscan-fast", "paper", "flic[fastdbscan]")],
)
def test_a_missing_extra_is_a_one_line_error_when_the_run_is_built(
    without_optional_packages, method, remover, hint
):
    from flic_cli.config import load_config
    from flic_cli.runs.pipeline import build_segmenter

    with pytest.raises(FlicInputError, match=re.escape(f"pip install '{hint}'")) as info:
        build_segmenter(load_config(), method, "ground", remover)
    assert "\n" not in str(info.value)
