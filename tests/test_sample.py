"""Tests of the embedded synthetic sample (scene generator, ray caster, writers)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from oracles import file_tree
from PIL import Image

from flic_cli import sample
from flic_cli.classes import CLASS_NAMES
from flic_cli.classes import THING_CLASSES as THINGS
from flic_cli.ground import paper_ground
from flic_cli.io import open_dataset
from flic_cli.projection import project_points

FRAMES = 3
ID = {name: cid for cid, name in CLASS_NAMES.items()}


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> sample.SamplePaths:
    return sample.write_sample(tmp_path_factory.mktemp("sample"), frames=FRAMES, seed=0)


def _read(paths: sample.SamplePaths, k: int) -> tuple[np.ndarray, np.ndarray]:
    seq = paths.kitti_sequence
    pts = np.fromfile(seq / "velodyne" / f"{k:06d}.bin", dtype="<f4").reshape(-1, 4)
    labels = np.fromfile(seq / "labels" / f"{k:06d}.label", dtype="<u4")
    return pts, labels


def test_pitch_table() -> None:
    p = sample.HDL64_PITCH_DEG
    assert p.shape == (64,)
    assert p[0] == pytest.approx(-1.9367) and p[-1] == pytest.approx(24.9992)
    assert np.all(np.diff(p) > 0)
    assert np.diff(p[:32]).mean() == pytest.approx(1 / 3, abs=0.02)
    assert np.diff(p[32:]).mean() == pytest.approx(0.5, abs=0.03)


@pytest.mark.slow
def test_deterministic(tmp_path: Path, written: sample.SamplePaths) -> None:
    again = sample.write_sample(tmp_path, frames=FRAMES, seed=0)
    root_a = written.kitti_root.parent
    a, b = file_tree(root_a), file_tree(again.kitti_root.parent)
    assert a.keys() == b.keys()
    assert all(a[k] == b[k] for k in a)
    assert again.kitti_root == tmp_path / "semantickitti"
    assert again.moosmann_log == tmp_path / "moosmann"


def test_frames_differ() -> None:
    r0, _, _ = sample.cast(
        sample.make_scene(0, 0),
        sample.HDL64_PITCH_DEG,
        sample.moosmann_azimuths(),
        np.random.default_rng(0),
    )
    r1, _, _ = sample.cast(
        sample.make_scene(0, 1),
        sample.HDL64_PITCH_DEG,
        sample.moosmann_azimuths(),
        np.random.default_rng(0),
    )
    assert np.mean(np.abs(r0 - r1) > 0.1) > 0.05
    assert sample.make_scene(0, 1).pose[0, 3] == pytest.approx(1.0)


def test_kitti_files(written: sample.SamplePaths) -> None:
    seq = written.kitti_sequence
    for k in range(FRAMES):
        size = (seq / "velodyne" / f"{k:06d}.bin").stat().st_size
        assert size % 16 == 0
        assert (seq / "labels" / f"{k:06d}.label").stat().st_size == size // 4
    assert len((seq / "poses.txt").read_text().splitlines()) == FRAMES
    assert len((seq / "times.txt").read_text().splitlines()) == FRAMES
    for line in (seq / "poses.txt").read_text().splitlines():
        assert len(line.split()) == 12
    calib = dict(line.split(":", 1) for line in (seq / "calib.txt").read_text().splitlines())
    assert set(calib) == {"P0", "P1", "P2", "P3", "Tr"}
    assert all(len(v.split()) == 12 for v in calib.values())


def test_scan_order_gives_64_rings(written: sample.SamplePaths) -> None:
    for k in range(FRAMES):
        pts, _ = _read(written, k)
        assert np.all(np.linalg.norm(pts[:, :3], axis=1) > 0)
        img = project_points(pts, width=2048, mode="rings")
        assert img.projection == "rings"
        assert img.shape == (64, 2048)
        assert img.coverage > 0.97
        # Row elevations follow the sensor table.
        assert np.allclose(np.degrees(img.elevation), -sample.HDL64_PITCH_DEG, atol=0.05)


def test_labels(written: sample.SamplePaths) -> None:
    for k in range(FRAMES):
        pts, labels = _read(written, k)
        sem, inst = labels & 0xFFFF, labels >> 16
        assert np.any(sem == ID["road"]) and np.any(sem == ID["car"])
        assert np.all(sem > 0)
        assert not np.any(inst[~np.isin(sem, THINGS)])
        assert np.all(inst[np.isin(sem, THINGS)] > 0)
        assert 0.0 <= pts[:, 3].min() and pts[:, 3].max() <= 1.0
        # An instance id belongs to one class only.
        for i in np.unique(inst[inst > 0]):
            assert np.unique(sem[inst == i]).size == 1


def test_moosmann_log(written: sample.SamplePaths) -> None:
    log = written.moosmann_log
    cfg = [ln for ln in (log / "img.cfg").read_text().splitlines() if not ln.startswith("#")]
    fields = [f.strip() for f in cfg[0].split(";") if f.strip()]
    assert fields[:4] == ["870", "64", "180", "-180"]
    assert np.allclose([float(f) for f in fields[4:]], sample.HDL64_PITCH_DEG, atol=1e-4)
    for k in range(FRAMES):
        with Image.open(log / f"scan{k:05d}.png") as im:
            assert im.mode in ("I;16", "I;16B", "I;16L")
            assert im.size == (870, 64)
            img = np.asarray(im)
        valid = int(np.count_nonzero(img))
        assert 40000 <= valid <= 48000
        assert img.max() <= sample.MAX_RANGE_M * 500 + 100
        sem, inst = written.moosmann_truth(k)
        assert sem.shape == (64, 870) and inst.shape == (64, 870)
        assert np.array_equal(sem > 0, img > 0)


def test_moosmann_geometry_matches_kitti() -> None:
    """Column c of the Moosmann image looks at yaw +180 - 360 c / 869 deg."""
    az = sample.moosmann_azimuths()
    assert np.degrees(az[0]) == pytest.approx(180.0) and np.degrees(az[-1]) == pytest.approx(-180)
    scene = sample.make_scene(0, 0)
    r, _, _ = sample.cast(scene, sample.HDL64_PITCH_DEG, az, np.random.default_rng(1))
    # Without the recording car, the lowest beam looking straight ahead (columns ~434.5) hits the
    # rising road at r = h / (sin(pitch) + slope cos(pitch)); looking back (column 0) the road
    # falls away.
    pitch = np.radians(sample.HDL64_PITCH_DEG[-1])
    slope = scene.ground.slope
    for cols, sgn in ((slice(433, 437), 1.0), (slice(0, 2), -1.0)):
        expect = sample.SENSOR_HEIGHT_M / (np.sin(pitch) + sgn * slope * np.cos(pitch))
        got = r[-1, cols]
        got = got[got > 0]
        assert got.size and np.all(np.abs(got - expect) < 0.06)
    # Every road return lies on the road plane z = -h + slope x, with or without the car.
    for vehicle in ((), sample.EGO_VEHICLE):
        r, sem, _ = sample.cast(
            scene, sample.HDL64_PITCH_DEG, az, np.random.default_rng(1), vehicle
        )
        rows, cols = np.nonzero(sem == ID["road"])
        assert rows.size > 500
        p = np.radians(sample.HDL64_PITCH_DEG)[rows]
        expect = sample.SENSOR_HEIGHT_M / (np.sin(p) + slope * np.cos(p) * np.cos(az[cols]))
        assert np.all(np.abs(r[rows, cols] - expect) < 0.08)


def test_recording_car_hides_the_lower_beams_ahead_and_behind() -> None:
    az = sample.moosmann_azimuths()
    scene = sample.make_scene(0, 0)
    free, _, _ = sample.cast(scene, sample.HDL64_PITCH_DEG, az, np.random.default_rng(3))
    hidden, sem, _ = sample.cast(
        scene, sample.HDL64_PITCH_DEG, az, np.random.default_rng(3), sample.EGO_VEHICLE
    )
    gone = (free > 0) & (hidden == 0)
    # The car only removes returns (the noise is drawn the same way); empty pixels have no label.
    assert np.array_equal(hidden[hidden > 0], free[hidden > 0])
    assert not sem[hidden == 0].any()
    # It hides the beams steeper than 14 deg ahead and 11 deg behind (10.6 deg past the rear
    # corners), none of the upper block, and sideways even the lowest beam clears it.
    pitch = sample.HDL64_PITCH_DEG
    assert not gone[pitch < 10.5].any()
    ahead, behind, left = 434, 0, 217
    assert (hidden[pitch > 14.5, ahead] == 0).all() and (free[pitch > 14.5, ahead] > 0).any()
    assert (hidden[pitch > 11.5, behind] == 0).all()
    assert (hidden[-1, left - 20 : left + 20] > 0).any()
    assert 7000 < int(gone.sum()) < 11000
    # Every row keeps returns on both sides.
    sides = np.abs(np.abs(np.degrees(az)) - 90.0) < 45.0
    assert (hidden[:, sides] > 0).sum(axis=1).min() > 50


def test_car_roofs(written: sample.SamplePaths) -> None:
    """Car roofs: car points high above the road on horizontal surfaces, above a window gap."""
    found = 0
    for k in range(FRAMES):
        pts, labels = _read(written, k)
        img = project_points(pts)
        sem = np.zeros(img.ranges.size, dtype=np.int64)
        sem[img.point_pixel] = labels & 0xFFFF
        sem = sem.reshape(img.shape)
        z = img.heights()
        r = img.ranges
        car = (sem == ID["car"]) & (r > 0)
        high = car & (z > -0.4)
        assert np.any(high)
        # Vertically adjacent roof pixels: same height, different range -> horizontal surface.
        pair = high[:-1] & high[1:]
        dz = np.abs(z[:-1] - z[1:])
        dr = np.abs(r[:-1] - r[1:])
        found += int(np.count_nonzero(pair & (dz < 0.05) & (dr > 0.1)))
    assert found > 20


def test_instances_and_scene_content() -> None:
    scene = sample.make_scene(0, 0)
    classes = {p.semantic for p in [*scene.boxes, *scene.cylinders]}
    names = {"building", "fence", "other-structure", "vegetation", "trunk", "pole"}
    names |= {"traffic-sign", "other-object", "car", "moving-car", "person", "bicyclist"}
    assert {ID[n] for n in names | {"bicycle"}} <= classes
    things = scene.instances
    assert all(c in THINGS for c in things.values())
    # Both kerbs are lined with parked cars over the 190 m street.
    parked = [p for p in scene.boxes if p.semantic in (ID["car"], ID["truck"]) and p.instance]
    assert 50 <= len({p.instance for p in parked}) <= 80
    assert {np.sign(p.center[1]) for p in parked} == {-1.0, 1.0}
    assert 1 <= sum(c == ID["moving-car"] for c in things.values()) <= 3
    assert 40 <= sum(c == ID["person"] for c in things.values()) <= 70
    assert 2 <= sum(c == ID["bicyclist"] for c in things.values()) <= 5
    for p in [*scene.boxes, *scene.cylinders]:
        assert (p.instance > 0) == (p.semantic in THINGS)


def test_moosmann_frames_look_like_real_logs(written: sample.SamplePaths) -> None:
    """Frame 0 of seed 0: valid and non-ground pixel counts in the range of real Moosmann frames.

    Real logs hold 40k-48k valid pixels of 870 x 64, 37k-43k after the paper's ground removal.
    """
    ds = open_dataset(written.moosmann_log)
    image = ds.load(ds.refs()[0]).image
    valid = int(np.count_nonzero(image.ranges > 0))
    non_ground = valid - int(np.count_nonzero(paper_ground(image)))
    assert 40000 <= valid <= 48000
    assert 37000 <= non_ground <= 43000
    # Some road and sidewalk is left for the ground extraction.
    assert 2000 <= valid - non_ground <= 8000


@pytest.mark.slow
def test_ensure_sample(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "cache" / "sample"
    monkeypatch.setenv("FLIC_SAMPLE_DIR", str(target))
    assert sample.default_sample_dir() == target
    first = sample.ensure_sample(frames=2, seed=0)
    assert (target / ".complete").is_file()
    assert first.kitti_root == target / "semantickitti"
    assert (first.kitti_sequence / "velodyne" / "000001.bin").is_file()
    assert (first.moosmann_log / "scan00001.png").is_file()
    stamp = (target / "moosmann" / "scan00000.png").stat().st_mtime_ns
    again = sample.ensure_sample(frames=2, seed=0)
    assert again.kitti_root == first.kitti_root
    assert (target / "moosmann" / "scan00000.png").stat().st_mtime_ns == stamp
    # No temporary folders are left beside the sample.
    assert [p.name for p in target.parent.iterdir()] == ["sample"]
    # Ground truth is available after a reuse too (recomputed deterministically).
    sem, _ = again.moosmann_truth(1)
    assert np.array_equal(sem, first.moosmann_truth(1)[0])


def test_default_sample_dir(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("FLIC_SAMPLE_DIR", raising=False)
    assert sample.default_sample_dir() == Path.home() / ".cache" / "flic" / "sample-v2"


def test_every_name_of_the_former_module_is_still_importable() -> None:
    """``flic_cli.sample`` was one module; its public names stay importable from the package."""
    former = [
        "EGO_VEHICLE", "HDL64_PITCH_DEG", "MAX_RANGE_M", "MOOSMANN_HEIGHT", "MOOSMANN_WIDTH",
        "SENSOR_HEIGHT_M", "Box", "Cylinder", "Ground", "SamplePaths", "Scene", "cast",
        "default_sample_dir", "ensure_sample", "kitti_azimuths", "make_scene",
        "moosmann_azimuths", "write_sample",
    ]  # fmt: skip
    assert set(former) <= set(sample.__all__)
    for name in sample.__all__:
        assert getattr(sample, name) is not None
