"""The entry points for targeted scenes: custom_scene, person, car, Ground, render_kitti,
render_moosmann and cast without noise, against hand-computed geometry."""

from __future__ import annotations

import numpy as np
import pytest

from flic_cli.classes import CLASS_NAMES
from flic_cli.io import open_dataset, read_bin, read_label
from flic_cli.sample import (
    EGO_VEHICLE,
    HDL64_PITCH_DEG,
    MAX_RANGE_M,
    SENSOR_HEIGHT_M,
    Box,
    Cylinder,
    Ground,
    Scene,
    car,
    cast,
    custom_scene,
    kitti_azimuths,
    make_scene,
    moosmann_azimuths,
    person,
    render_kitti,
    render_moosmann,
)

ID = {name: cid for cid, name in CLASS_NAMES.items()}
ROAD, SIDEWALK, TERRAIN = ID["road"], ID["sidewalk"], ID["terrain"]
PERSON, CAR, BUILDING = ID["person"], ID["car"], ID["building"]
H = SENSOR_HEIGHT_M


def wall(x: float, half_width: float) -> Scene:
    """A wall whose face lies at x (2 m thick, 20 m high), nothing else: no ground."""
    box = Box((x + 1.0, 0.0, 0.0), (1.0, half_width, 10.0), 0.0, BUILDING)
    return Scene(0, 0, np.eye(3, 4), None, [box], [])


def test_a_wall_comes_back_at_its_range_in_the_columns_that_face_it() -> None:
    frame = render_moosmann(wall(19.5, 2.0))
    image = frame.image
    az = moosmann_azimuths()
    el = -np.radians(HDL64_PITCH_DEG)
    rows, cols = np.nonzero(image.ranges > 0)
    # Exactly the columns whose yaw lies within atan(2 / 19.5) = 5.86 deg of straight ahead (14
    # each side at 360 / 869 deg apart, the middle two at +-0.21 deg), every row (the wall spans
    # +-27 deg vertically at 19.5 m).
    facing = np.flatnonzero(np.abs(az) <= np.arctan2(2.0, 19.5))
    assert facing.size == 28 and set(cols) == set(facing)
    assert set(rows) == set(range(64))
    expect = 19.5 / (np.cos(el[rows]) * np.cos(az[cols]))
    np.testing.assert_allclose(image.ranges[rows, cols], expect, atol=0.0011)  # PNG: 2 mm
    assert (frame.semantic[rows, cols] == BUILDING).all() and not frame.instance.any()
    assert not frame.semantic[image.ranges == 0].any()
    assert image.projection == "native" and image.shape == (64, 870)
    # The points as the Moosmann loader gives them lie on the wall's face (within 2 mm: the
    # loader's column yaw, 180 - 360 (c + 0.5) / 870 deg, differs from the sensor's
    # 180 - 360 c / 869 deg by up to 0.03 deg this close to straight ahead).
    pts = image.to_points()[image.point_pixel]
    assert pts.shape == (rows.size, 3)
    np.testing.assert_allclose(pts[:, 0], 19.5, atol=0.002)
    assert np.abs(pts[:, 1]).max() < 2.0


def test_render_kitti_gives_the_points_ring_after_ring() -> None:
    width = 1024
    points, labels = render_kitti(wall(19.5, 2.0), width=width)
    az = kitti_azimuths(width)
    per_ring = int(np.count_nonzero(np.abs(np.angle(np.exp(1j * az))) <= np.arctan2(2.0, 19.5)))
    assert points.shape == (64 * per_ring, 4) and points.dtype == np.float32
    np.testing.assert_allclose(points[:, 0], 19.5, atol=1e-4)
    assert np.abs(points[:, 1]).max() <= 2.0 + 1e-4
    # Ring after ring from the top beam down; within a ring counter-clockwise from azimuth 0.
    elevation = np.degrees(np.arcsin(points[:, 2] / np.linalg.norm(points[:, :3], axis=1)))
    rings = elevation.reshape(64, per_ring)
    np.testing.assert_allclose(rings, -HDL64_PITCH_DEG[:, None] * np.ones(per_ring), atol=1e-3)
    first = np.arctan2(points[:per_ring, 1], points[:per_ring, 0]) % (2 * np.pi)
    expect = np.sort(az[np.abs(np.angle(np.exp(1j * az))) <= np.arctan2(2.0, 19.5)])
    np.testing.assert_allclose(first, expect, atol=1e-5)
    assert (labels == BUILDING).all() and labels.dtype == np.uint32
    # Without noise the remission is the class's base remission.
    assert np.unique(points[:, 3]).size == 1


def test_flat_ground_returns_the_road_at_h_over_sin_pitch() -> None:
    r, sem, inst = cast(custom_scene(), HDL64_PITCH_DEG, moosmann_azimuths(), noise=False)
    pitch = np.radians(HDL64_PITCH_DEG)
    expect = np.where(pitch > 0, H / np.sin(np.maximum(pitch, 1e-9)), np.inf)
    seen = expect <= MAX_RANGE_M
    np.testing.assert_allclose(
        r[seen], np.broadcast_to(expect[seen, None], r[seen].shape), rtol=1e-6
    )
    assert (sem[seen] == ROAD).all() and not r[~seen].any() and not inst.any()


def test_kerb_sidewalk_and_terrain_to_the_right() -> None:
    """Looking right (yaw -90 deg) over a road 3 m wide to each side, a 0.12 m kerb, a sidewalk
    to 6 m and terrain beyond: the road, the kerb face, the sidewalk and the terrain come back
    where the geometry puts them."""
    g = Ground(slope=0.0, road_y=(-3.0, 3.0), sidewalk_y=(-6.0, 6.0), kerb_height=0.12)
    pitch = np.linspace(10.0, 40.0, 301)
    p = np.radians(pitch)
    r, sem, _ = cast(custom_scene(ground=g), pitch, np.array([-np.pi / 2]), noise=False)
    r, sem = r[:, 0].astype(np.float64), sem[:, 0]
    on_road = H / np.tan(p) < 3.0
    face_z = -3.0 * np.tan(p)  # height of the ray where it crosses the kerb line
    on_face = ~on_road & (face_z >= -H) & (face_z <= -H + 0.12)
    top = ~on_road & ~on_face
    reach = (H - 0.12) / np.tan(p)  # horizontal distance where it meets the raised level
    assert on_road.sum() > 10 and on_face.sum() >= 1 and top.sum() > 10
    np.testing.assert_allclose(r[on_road], H / np.sin(p[on_road]), rtol=1e-5)
    np.testing.assert_allclose(r[on_face], 3.0 / np.cos(p[on_face]), rtol=1e-5)
    np.testing.assert_allclose(r[top], (H - 0.12) / np.sin(p[top]), rtol=1e-5)
    assert (sem[on_road] == ROAD).all() and (sem[on_face] == SIDEWALK).all()
    assert (sem[top & (reach < 6.0)] == SIDEWALK).all()
    assert (sem[top & (reach > 6.0)] == TERRAIN).all()
    assert g.height(0.0, -2.0) == pytest.approx(-H) and g.height(5.0, -4.0) == pytest.approx(
        -H + 0.12
    )


@pytest.mark.parametrize("slope_deg", [2.0, -3.0])
def test_a_slope_brings_the_road_closer_ahead_and_further_behind(slope_deg: float) -> None:
    slope = np.tan(np.radians(slope_deg))
    scene = custom_scene(ground=Ground.flat(slope=slope))
    pitch = HDL64_PITCH_DEG[40:]
    p = np.radians(pitch)
    r, _, _ = cast(scene, pitch, np.array([0.0, np.pi]), noise=False)
    np.testing.assert_allclose(r[:, 0], H / (np.sin(p) + slope * np.cos(p)), rtol=1e-5)
    np.testing.assert_allclose(r[:, 1], H / (np.sin(p) - slope * np.cos(p)), rtol=1e-5)


def test_two_people_one_metre_apart_on_a_sidewalk() -> None:
    g = Ground(slope=0.0, road_y=(-2.0, 2.0), sidewalk_y=(-5.0, 5.0))
    a, b = person(8.0, -3.0, 1, ground=g), person(8.0, -4.0, 2, ground=g)
    # They stand on the sidewalk, 0.12 m above the road.
    assert a.center[2] - a.half[2] == pytest.approx(-H + 0.12)
    assert (a.semantic, a.instance, b.instance) == (PERSON, 1, 2)
    scene = custom_scene(a, b, ground=g)
    assert scene.instances == {1: PERSON, 2: PERSON}
    frame = render_moosmann(scene)
    az = moosmann_azimuths()
    for inst, y in ((1, -3.0), (2, -4.0)):
        rows, cols = np.nonzero(frame.instance == inst)
        assert rows.size > 20
        assert (frame.semantic[rows, cols] == PERSON).all()
        # Their columns look at them: yaw within the box's angular extent around atan2(y, 8).
        yaw = az[cols]
        assert np.all(np.abs(yaw - np.arctan2(y, 8.0)) < 0.06)
        # Every point of the person lies inside its box (x from 7.75 m, the face towards us).
        pts = frame.image.to_points().reshape(64, 870, 3)[rows, cols]
        assert pts[:, 0].min() > 7.74 and pts[:, 2].min() > -H + 0.12 - 0.01
    # The two are separated: their columns do not overlap.
    c1 = set(np.nonzero(frame.instance == 1)[1])
    c2 = set(np.nonzero(frame.instance == 2)[1])
    assert not c1 & c2


def test_a_car_twenty_metres_ahead() -> None:
    parts = car(20.0, 0.0, 3)
    assert len(parts) == 8 and {p.instance for p in parts} == {3}
    points, labels = render_kitti(custom_scene(parts))
    mine = labels >> 16 == 3
    assert mine.sum() > 100 and ((labels[mine] & 0xFFFF) == CAR).all()
    # The front of its body faces the sensor at 20 - 4.4 / 2 = 17.8 m; it stands on the road.
    assert points[mine, 0].min() == pytest.approx(17.8, abs=1e-3)
    assert points[mine, 2].min() >= -H + 0.22 - 1e-3
    road = (labels & 0xFFFF) == ROAD
    assert road.sum() > 10000 and not (labels[road] >> 16).any()
    # Moved 5 m closer, the car's front comes back at 12.8 m.
    near, near_labels = render_kitti(custom_scene(parts).seen_from(5.0))
    assert near[near_labels >> 16 == 3, 0].min() == pytest.approx(12.8, abs=1e-3)


def test_seen_from_moves_everything_and_rides_the_slope() -> None:
    g = Ground(slope=0.05, road_y=(-2.0, 3.0), sidewalk_y=(-5.0, 6.0))
    scene = custom_scene(
        Box((10.0, 1.0, 0.0), (1.0, 1.0, 1.0), 0.0, BUILDING),
        Cylinder((4.0, -3.0), 0.1, -1.0, 2.0, ID["pole"]),
        ground=g,
    )
    moved = scene.seen_from(4.0, 1.0)
    assert moved.boxes[0].center == pytest.approx((6.0, 0.0, -0.2))
    c = moved.cylinders[0]
    assert c.center == pytest.approx((0.0, -4.0)) and (c.z_min, c.z_max) == pytest.approx(
        (-1.2, 1.8)
    )
    assert moved.ground.road_y == (-3.0, 2.0) and moved.ground.sidewalk_y == (-6.0, 5.0)
    np.testing.assert_allclose(moved.pose[:, 3], [4.0, 1.0, 0.2])
    # The road under the moved sensor is still the sensor height below it.
    assert moved.ground.height(0.0, 0.0) == pytest.approx(-H)


def test_custom_scene_takes_primitives_and_iterables_of_them() -> None:
    pole = Cylinder((3.0, 0.0), 0.1, -H, 2.0, ID["pole"])
    scene = custom_scene(car(10.0, 0.0, 1), pole, [person(5.0, 2.0, 2)])
    assert len(scene.boxes) == 9 and scene.cylinders == [pole]
    assert scene.ground == Ground.flat()
    with pytest.raises(TypeError, match="expected a Box, a Cylinder"):
        custom_scene(3.0)  # type: ignore[arg-type]


def test_noise_is_reproducible_and_off_by_default() -> None:
    scene = custom_scene(car(12.0, 3.0, 1))
    exact = render_moosmann(scene)
    assert np.array_equal(render_moosmann(scene).image.ranges, exact.image.ranges)
    noisy_a = render_moosmann(scene, noise=True, rng=np.random.default_rng(5))
    noisy_b = render_moosmann(scene, noise=True, rng=np.random.default_rng(5))
    assert np.array_equal(noisy_a.image.ranges, noisy_b.image.ranges)
    both = (noisy_a.image.ranges > 0) & (exact.image.ranges > 0)
    diff = noisy_a.image.ranges[both] - exact.image.ranges[both]
    assert 0.01 < diff.std() < 0.02  # 1.5 cm range noise
    assert (noisy_a.image.ranges > 0).sum() < (exact.image.ranges > 0).sum()  # dropouts


def test_the_sample_files_are_these_renders(small_sample) -> None:
    """Frame 1 of the written sample is render_kitti / render_moosmann of make_scene(0, 1) with
    the writer's noise streams."""
    k = 1
    scene = make_scene(0, k)
    points, labels = render_kitti(scene, noise=True, rng=np.random.default_rng([0, k, 1]))
    seq = small_sample.kitti_sequence
    assert np.array_equal(read_bin(seq / "velodyne" / f"{k:06d}.bin"), points)
    assert np.array_equal(read_label(seq / "labels" / f"{k:06d}.label"), labels)
    frame = render_moosmann(
        scene, noise=True, rng=np.random.default_rng([0, k, 2]), vehicle=EGO_VEHICLE
    )
    ds = open_dataset(small_sample.moosmann_log)
    loaded = ds.load(ds.refs()[k]).image
    assert np.array_equal(loaded.ranges, frame.image.ranges)
    np.testing.assert_allclose(loaded.elevation, frame.image.elevation, atol=1e-6)
    sem, inst = small_sample.moosmann_truth(k)
    assert np.array_equal(sem, frame.semantic) and np.array_equal(inst, frame.instance)


def test_the_package_docstring_example_runs() -> None:
    """The example of ``flic_cli.sample``'s docstring: two people 1 m apart and a car."""
    import textwrap

    import flic_cli.sample

    lines = flic_cli.sample.__doc__.split("a car 20 m ahead::\n", 1)[1].splitlines()
    block = []
    for line in lines:
        if line and not line.startswith("    "):
            break
        block.append(line)
    namespace: dict = {}
    exec(textwrap.dedent("\n".join(block)), namespace)
    points, labels = namespace["points"], namespace["labels"]
    assert set(np.unique(labels >> 16)) == {0, 1, 2, 3}
    assert namespace["image"].shape == (64, 870)
    assert set(np.unique(namespace["instance"])) == {0, 1, 2, 3}
    assert points.shape[0] == labels.shape[0]
