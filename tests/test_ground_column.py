"""flic's ``column`` ground remover on synthetic geometry: kerbs, slopes, a car roof at 20 m,
people on a sidewalk (scenes built with the sample's ray caster, labels from the scene); the
optimised kernel against the previous implementation, kept below as the reference; step 6 (row
neighbours) on hand-built rows."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numba import njit

from flic_cli.ground import REMOVERS, ColumnGround
from flic_cli.ground.base import Ground as GroundStep
from flic_cli.ground.base import leave_pixels
from flic_cli.io import open_dataset
from flic_cli.range_image import RangeImage, from_sensor_image
from flic_cli.sample import HDL64_PITCH_DEG, Box, Cylinder, Ground, Scene, cast, kitti_azimuths

H_S = 1.73


def column_ground(image: RangeImage, held: np.ndarray | None = None, **kw: object) -> np.ndarray:
    """The column remover's ground pixels of ``image`` with the parameters ``kw`` (steps 1-6; the
    mask does not depend on steps 7 and 8); ``held``, if given, is filled with step 8's held
    cells: those step 6 would take but for the foot and under test."""
    ground = ColumnGround(**{"hidden_points": False, **kw}).extract(image, None)
    if held is not None:
        held[...] = ground.held
    return ground.mask


def _scene(ground: Ground, boxes=(), cylinders=()) -> Scene:
    pose = np.hstack([np.eye(3), np.zeros((3, 1))])
    return Scene(0, 0, pose, ground, list(boxes), list(cylinders))


def _image(scene: Scene, seed: int = 0) -> tuple[RangeImage, np.ndarray, np.ndarray]:
    ranges, sem, inst = cast(
        scene, HDL64_PITCH_DEG, kitti_azimuths(2048), np.random.default_rng(seed)
    )
    return from_sensor_image(ranges, -np.radians(HDL64_PITCH_DEG)), sem, inst


def _car(x: float, y: float, zg: float, instance: int) -> list[Box]:
    """A car standing on the ground at height zg: body 0.25-1.0 m, cabin up to 1.45 m."""
    body = Box((x, y, zg + 0.625), (2.1, 0.9, 0.375), 0.0, 10, instance)
    cabin = Box((x - 0.3, y, zg + 1.225), (1.1, 0.8, 0.225), 0.0, 10, instance)
    return [body, cabin]


def _person(x: float, y: float, zg: float, instance: int) -> Cylinder:
    return Cylinder((x, y), 0.25, zg, zg + 1.75, 30, instance)


STREET = Ground(slope=0.0, road_y=(-4.0, 4.0), sidewalk_y=(-7.5, 7.5), kerb_height=0.15)


def test_a_street_with_kerbs_is_ground_up_to_the_buildings():
    image, sem, _ = _image(_scene(STREET))
    ground = column_ground(image)
    valid = image.ranges > 0
    road, walk = valid & (sem == 40), valid & (sem == 48)
    near = image.ranges < 30
    assert ground[road & near].mean() > 0.97
    assert ground[walk & near].mean() > 0.95  # the 0.15 m kerb step is climbed
    assert not ground[~valid].any()


def test_a_road_that_rises_at_4_degrees_is_ground():
    # The sample's ground is one plane through the wheels: 4 deg up ahead, down behind. (A plane
    # that rises faster than about 4.5 deg from right under the car is not seeded ahead: the seed
    # tolerance grows by 2 deg with range.)
    slope = Ground(slope=float(np.tan(np.radians(4.0))), road_y=(-6, 6), sidewalk_y=(-9, 9))
    image, sem, _ = _image(_scene(slope))
    ground = column_ground(image)
    road = (image.ranges > 0) & (sem == 40) & (image.ranges < 30)
    assert ground[road].mean() > 0.95


def test_a_car_roof_at_20_m_is_kept_and_the_road_around_it_removed():
    car = _car(20.0, -1.5, -H_S, instance=1)
    image, sem, inst = _image(_scene(STREET, car))
    ground = column_ground(image)
    valid = image.ranges > 0
    z = image.heights()
    is_car = valid & (inst == 1)
    roof = is_car & (z > -H_S + 1.2)
    assert roof.sum() > 50
    assert not ground[roof].any()
    assert ground[is_car].mean() < 0.03  # at most the lowest row, at road level
    assert ground[is_car & (z > -H_S + 0.15)].mean() == 0.0
    road = valid & (sem == 40) & (image.ranges < 30)
    assert ground[road].mean() > 0.95


def test_people_on_the_sidewalk_are_kept_and_the_sidewalk_removed():
    zg = -H_S + STREET.kerb_height
    people = [_person(x, 5.5, zg, instance=k + 1) for k, x in enumerate((6.0, 9.0, 13.0))]
    image, sem, inst = _image(_scene(STREET, cylinders=people))
    ground = column_ground(image)
    valid = image.ranges > 0
    z = image.heights()
    for k in range(1, 4):
        person = valid & (inst == k)
        assert person.sum() > 100
        # at most the soles: the base band takes cells within 0.1 m of the ground
        assert ground[person].mean() < 0.08
        assert not ground[person & (z > zg + 0.15)].any()
    walk = valid & (sem == 48) & (image.ranges < 20)
    assert ground[walk].mean() > 0.95


def test_a_wall_and_an_empty_image_have_no_ground():
    elevation = np.radians(np.linspace(-2, -20, 16))
    wall = (5.0 / np.cos(elevation)).astype(np.float32)[:, None].repeat(8, 1)
    image = RangeImage(wall, elevation, np.arange(wall.size), "native", one_point_per_pixel=True)
    assert not column_ground(image).any()
    empty = RangeImage(
        np.zeros((4, 8), np.float32),
        elevation[:4],
        np.zeros(0, np.int64),
        "native",
        one_point_per_pixel=True,
    )
    assert not column_ground(empty).any()


@settings(max_examples=40, deadline=None)
@given(arrays(np.float32, (8, 12), elements=st.sampled_from([0.0, 2.0, 4.5, 7.0, 12.0, 30.0])))
def test_empty_pixels_are_never_ground(ranges):
    elevation = np.radians(np.linspace(-3, -24, 8))
    image = RangeImage(
        ranges, elevation, np.flatnonzero(ranges.reshape(-1)), "native", one_point_per_pixel=True
    )
    ground = column_ground(image)
    assert ground.shape == ranges.shape
    assert not ground[ranges == 0].any()


def test_column_is_a_registered_component_with_validated_parameters():
    assert REMOVERS["column"] is ColumnGround
    with pytest.raises(ValueError):
        ColumnGround(noise_m=-1.0)
    image, _, _ = _image(_scene(STREET))
    assert np.array_equal(ColumnGround().extract(image, None).mask, column_ground(image))


# ---- the previous implementation (flic 4eec351), the reference of the optimised kernel ----------
# Same steps 1-5, written with per-call trigonometry and a first pass of its own; the optimised
# kernel must give the same masks with step 6 off (neighbour_px=0). Its column models and their
# arithmetic are float32 since the kernel keeps them so (it was float64 at 4eec351).

_BEHIND_M = 0.05  # a cell nearer than the last ground point by more than this is an object
_GAP_SLOPE_DEG = 5.0  # slope change allowed per metre of gap for a step
_SEED_SLOPE_DEG = 2.0  # seed tolerance grows with range at this slope
_FAR_DR_M = 0.5  # beyond this gap a continuation checks the cell above for an object
_RUN_CELLS = 3  # cells above that confirm a step or a seed
_RUN_MIN_CELLS = 2  # ...at least this many of them
_RUN_ROWS = 6  # ...found within this many rows
_RUN_JUMP = 0.3  # a cell farther than this share of rho ends the run (a depth jump)
_OCCLUDER_M = 0.15  # a cell above nearer by more than this (+2 % of rho) occludes the cell
_OCCLUDER_REL = 0.02
_GAIN_HEIGHT = 0.5  # alpha-beta filter of the ground model
_GAIN_GRADIENT = 0.3
_GAIN_BASE_M = 1.0  # the gradient update divides by max(dr, this)
_MAX_GRADIENT_DEG = 10.0
_BASE_DR_M = 1.0  # the base band applies within this distance beyond the last ground point


@njit(cache=True)
def _ref_surface_above(
    rho_img: np.ndarray,
    z_img: np.ndarray,
    r: int,
    c: int,
    rho: float,
    z: float,
    grad: float,
    noise: float,
    tan_flat: float,
) -> int:

    n = 0
    prev = rho
    run_rho = rho
    run_z = z
    lo = r - 1 - _RUN_ROWS
    if lo < -1:
        lo = -1
    for ra in range(r - 1, lo, -1):
        ra_rho = rho_img[ra, c]
        if ra_rho <= 0.0:
            continue
        ra_z = z_img[ra, c]
        if ra_rho < prev - _BEHIND_M or ra_rho > prev + _RUN_JUMP * prev:
            if n == 0:
                if ra_rho < prev - _OCCLUDER_M - _OCCLUDER_REL * prev:
                    return 2
                return 0
            break
        ddr = ra_rho - rho
        if ddr < 0.0:
            ddr = 0.0
        # every cell within a loose band, the end of the run within the flat band
        if abs(ra_z - z - grad * ddr) > 2.0 * noise + tan_flat * ddr:
            return 0
        prev = ra_rho
        run_rho = ra_rho
        run_z = ra_z
        n += 1
        if n >= _RUN_CELLS:
            break
    if n == 0:
        return 2
    if n < _RUN_MIN_CELLS:
        return 0
    ddr = run_rho - rho
    if ddr < 0.0:
        ddr = 0.0
    return 1 if abs(run_z - z - grad * ddr) <= noise + tan_flat * ddr else 0


@njit(cache=True)
def _ref_column_ground(
    ranges: np.ndarray,
    sin_el: np.ndarray,
    cos_el: np.ndarray,
    sensor_height: float,
    noise: float,
    tan_change: float,
    kerb: float,
    max_step: float,
    tan_flat: float,
    seed_tol: float,
    base_band: float,
) -> np.ndarray:
    h, w = ranges.shape
    # horizontal range and height of every pixel (0, 0 where empty: cos(elevation) > 0)
    rho_img = np.empty((h, w), dtype=np.float32)
    z_img = np.empty((h, w), dtype=np.float32)
    for r in range(h):
        se = np.float32(sin_el[r])
        ce = np.float32(cos_el[r])
        for c in range(w):
            rho_img[r, c] = ranges[r, c] * ce
            z_img[r, c] = ranges[r, c] * se
    # the column models and their arithmetic in float32, as the kernel keeps them
    f = np.float32
    tan_gap = f(np.tan(np.radians(_GAP_SLOPE_DEG)))
    tan_seed = f(np.tan(np.radians(_SEED_SLOPE_DEG)))
    max_grad = f(np.tan(np.radians(_MAX_GRADIENT_DEG)))
    noise32, kerb32, tan_change32 = f(noise), f(kerb), f(tan_change)
    sensor32, seed_tol32, base_band32, max_step32 = (
        f(sensor_height), f(seed_tol), f(base_band), f(max_step))  # fmt: skip
    out = np.zeros((h, w), dtype=np.bool_)
    g_rho = np.full(w, f(-1.0))  # last ground point of the column (-1: none yet)
    g_z = np.zeros(w, dtype=np.float32)
    g_m = np.zeros(w, dtype=np.float32)  # ground gradient
    last = np.zeros(w, dtype=np.bool_)  # the column's previous valid cell was ground
    for r in range(h - 1, -1, -1):
        for c in range(w):
            rho = rho_img[r, c]
            if rho <= 0.0:
                continue
            z = z_img[r, c]
            cont = False
            dr = f(0.0)
            e = f(0.0)
            if g_rho[c] >= 0.0:
                dr = rho - g_rho[c]
                if dr < -f(_BEHIND_M):  # 1. in front of the ground: an object
                    last[c] = False
                    continue
                if dr < 0.0:
                    dr = f(0.0)
                e = z - (g_z[c] + g_m[c] * dr)
                band = noise32 + tan_change32 * dr
                if last[c] and -band <= e <= band:  # 2. continuation
                    ok = True
                    cont = True
                    if dr > _FAR_DR_M:
                        for ra in range(r - 1, -1, -1):
                            ra_rho = rho_img[ra, c]
                            if ra_rho > 0.0:
                                stands = abs(ra_rho - rho) < f(0.25) * dr
                                if stands and z_img[ra, c] > z:
                                    ok = False
                                break
                else:  # 3. step
                    lim = noise32 + kerb32 + tan_gap * dr
                    if lim > max_step32:
                        lim = max_step32
                    ok = -(noise32 + kerb32 + f(3.0) * tan_gap * dr) <= e <= lim
                    if ok:
                        s = _ref_surface_above(
                            rho_img, z_img, r, c, rho, z, g_m[c], noise, tan_flat
                        )
                        ok = s == 1 or (s == 2 and abs(e) <= min(band, base_band32))
            else:  # 4. seed
                e = z + sensor32
                lim = seed_tol32 + tan_seed * rho
                ok = -lim <= e <= lim
                if ok:
                    s = _ref_surface_above(rho_img, z_img, r, c, rho, z, f(0.0), noise, tan_flat)
                    ok = s == 1 or (s == 2 and abs(e) <= base_band32)
            if ok:
                if cont:
                    m = g_m[c] + f(_GAIN_GRADIENT) * e / max(dr, f(_GAIN_BASE_M))
                    g_z[c] = g_z[c] + g_m[c] * dr + f(_GAIN_HEIGHT) * e
                    g_m[c] = min(max(m, -max_grad), max_grad)
                else:
                    g_z[c] = z
                g_rho[c] = rho
                out[r, c] = True
                last[c] = True
            else:
                last[c] = False
                # 5. base band: ground level just beyond the last ground point
                if g_rho[c] >= 0.0 and dr < _BASE_DR_M and -base_band32 <= e <= base_band32:
                    out[r, c] = True
    return out


def _reference(image: RangeImage, **kw) -> np.ndarray:
    p = dict(sensor_height_m=1.73, noise_m=0.03, slope_change_deg=1.0, kerb_m=0.2,
             max_step_m=0.4, flat_deg=15.0, seed_tolerance_m=0.2, base_band_m=0.05)  # fmt: skip
    p.update(kw)
    el = np.asarray(image.elevation, dtype=np.float64)
    return _ref_column_ground(
        np.ascontiguousarray(image.ranges, dtype=np.float32),
        np.sin(el),
        np.cos(el),
        float(p["sensor_height_m"]),
        float(p["noise_m"]),
        float(np.tan(np.radians(p["slope_change_deg"]))),
        float(p["kerb_m"]),
        float(p["max_step_m"]),
        float(np.tan(np.radians(p["flat_deg"]))),
        float(p["seed_tolerance_m"]),
        float(p["base_band_m"]),
    )


SETTINGS = [{}, {"base_band_m": 0.1, "kerb_m": 0.1, "noise_m": 0.05}, {"max_step_m": 0.6}]


@pytest.mark.slow
@pytest.mark.parametrize("kw", SETTINGS)
def test_kernel_equals_the_previous_implementation_on_synthetic_streets(kw):
    scenes = [_scene(STREET), _scene(STREET, _car(20.0, -1.5, -H_S, 1))]
    slope = Ground(slope=float(np.tan(np.radians(4.0))), road_y=(-6, 6), sidewalk_y=(-9, 9))
    scenes.append(_scene(slope))
    for seed, scene in enumerate(scenes):
        image, _, _ = _image(scene, seed)
        assert np.array_equal(column_ground(image, neighbour_px=0, **kw), _reference(image, **kw))


@pytest.mark.slow
@pytest.mark.parametrize("kw", SETTINGS[:2])
def test_kernel_equals_the_previous_implementation_on_the_shared_frames(kitti_root, kw):
    from flic_cli.config import load_config
    from flic_cli.runs.pipeline import prepare

    cfg = load_config()
    ds = open_dataset(kitti_root)
    for ref in ds.refs()[::5]:
        image = prepare(ds.load(ref), "ground", cfg.projection).image
        got = column_ground(image, neighbour_px=0, point_heights=False, **kw)
        assert np.array_equal(got, _reference(image, **kw))


#: Random 10 x 14 images of a few ranges (steps, near-equal neighbours, empty cells), the input
#: of the property tests below
RANDOM_RANGES = arrays(
    np.float32, (10, 14), elements=st.sampled_from([0.0, 3.0, 3.1, 4.5, 6.0, 6.2, 9.0, 25.0])
)


def _random_image(ranges: np.ndarray) -> RangeImage:
    """A sensor's own image of ``ranges`` with rows from -2 to -24 deg."""
    elevation = np.radians(np.linspace(-2, -24, 10))
    return RangeImage(
        ranges, elevation, np.flatnonzero(ranges.reshape(-1)), "native", one_point_per_pixel=True
    )


@settings(max_examples=60, deadline=None)
@given(RANDOM_RANGES)
def test_kernel_equals_the_previous_implementation_on_random_images(ranges):
    image = _random_image(ranges)
    assert np.array_equal(column_ground(image, neighbour_px=0), _reference(image))


# ---- step 6 written plainly, the reference of the kernel's runs -----------------------------


@njit(cache=True)
def _ref_row_neighbours(ranges, sin_el, cos_el, cols, nb_px, nb_band, tan_foot, under, tan_face):
    """Step 6 cell by cell on top of the columns' mask ``cols``: the nearest cell of ``cols`` on
    each side within ``nb_px`` columns at the same range (1 m) and height (``nb_band``), unless
    the next valid cell above (2 rows) is a foot's or a near occluder's, or the next valid cell
    below (2 rows) is not ground and lies under the cell's face. Rows from the bottom up: the
    face test reads the final decision of the rows below."""
    h, w = ranges.shape
    out = cols.copy()
    for r in range(h - 1, -1, -1):
        se = np.float32(sin_el[r])
        ce = np.float32(cos_el[r])
        for c in range(w):
            rho = ranges[r, c] * ce
            if rho <= 0.0 or cols[r, c]:
                continue
            z = ranges[r, c] * se
            hit = False
            for side in (-1, 1):
                q = c + side
                while 0 <= q < w and not cols[r, q]:
                    q += side
                if 0 <= q < w and abs(q - c) <= nb_px and not hit:
                    q_rho = ranges[r, q] * ce
                    q_z = ranges[r, q] * se
                    hit = abs(rho - q_rho) <= 1.0 and abs(z - q_z) <= nb_band
            if not hit:
                continue
            stood = False
            for ra in range(r - 1, max(r - 3, -1), -1):
                ra_rho = ranges[ra, c] * np.float32(cos_el[ra])
                if ra_rho > 0.0:
                    d = ra_rho - rho
                    if d < -0.3:
                        stood = d > -under
                    else:
                        stood = ranges[ra, c] * np.float32(sin_el[ra]) - z > tan_foot * abs(d)
                    break
            face = False
            for rb in range(r + 1, min(r + 3, h)):
                rb_rho = ranges[rb, c] * np.float32(cos_el[rb])
                if rb_rho > 0.0:
                    rb_z = ranges[rb, c] * np.float32(sin_el[rb])
                    face = not out[rb, c] and z - rb_z > tan_face * abs(rho - rb_rho)
                    break
            out[r, c] = not stood and not face
    return out


def _reference_full(
    image: RangeImage, nb_px=10, nb_band=0.08, foot_deg=30.0, under=2.0, face_deg=30.0, **kw
):
    el = np.asarray(image.elevation, dtype=np.float64)
    ranges = np.ascontiguousarray(image.ranges, dtype=np.float32)
    cols = _reference(image, **kw)
    tan_foot = float(np.tan(np.radians(foot_deg)))
    tan_face = float(np.tan(np.radians(face_deg))) if face_deg < 90 else np.inf
    return _ref_row_neighbours(
        ranges, np.sin(el), np.cos(el), cols, nb_px, nb_band, tan_foot, under, tan_face
    )


STEP6 = [
    {},
    {"nb_px": 3, "nb_band": 0.03, "under": 0.0, "face_deg": 90.0},
    {"nb_px": 40, "foot_deg": 60.0, "face_deg": 15.0},
]


def _kw6(kw):
    names = {"nb_px": "neighbour_px", "nb_band": "neighbour_band_m", "under": "under_m"}
    return {names.get(k, k): v for k, v in kw.items()}


@pytest.mark.slow
@pytest.mark.parametrize("kw", STEP6)
def test_step_6_equals_the_plain_reference_on_synthetic_streets(kw):
    zg = -H_S + STREET.kerb_height
    people = [_person(x, 5.5, zg, instance=k + 1) for k, x in enumerate((6.0, 9.0, 13.0))]
    scenes = [_scene(STREET, _car(20.0, -1.5, -H_S, 1), people), _scene(STREET)]
    for seed, scene in enumerate(scenes):
        image, _, _ = _image(scene, seed)
        assert np.array_equal(column_ground(image, **_kw6(kw)), _reference_full(image, **kw))


@pytest.mark.slow
@pytest.mark.parametrize("kw", STEP6[:2])
def test_step_6_equals_the_plain_reference_on_the_shared_frames(kitti_root, kw):
    from flic_cli.config import load_config
    from flic_cli.runs.pipeline import prepare

    cfg = load_config()
    ds = open_dataset(kitti_root)
    for ref in ds.refs()[2::5]:
        image = prepare(ds.load(ref), "ground", cfg.projection).image
        got = column_ground(image, point_heights=False, **_kw6(kw))
        assert np.array_equal(got, _reference_full(image, **kw))


@settings(max_examples=60, deadline=None)
@given(RANDOM_RANGES, st.integers(1, 6))
def test_step_6_equals_the_plain_reference_on_random_images(ranges, nb_px):
    image = _random_image(ranges)
    got = column_ground(image, neighbour_px=nb_px, neighbour_band_m=0.5)
    assert np.array_equal(got, _reference_full(image, nb_px=nb_px, nb_band=0.5))


# ---- step 6: row neighbours ------------------------------------------------------------------

ROW_DIST = np.array([14.4, 12.0, 10.2, 8.9, 7.8])  # where each row meets a flat road 1.73 m down


def _road_rows(w: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """(rho, z) of five rows of a flat road 1.73 m below the sensor, ``w`` columns."""
    rho = np.repeat(ROW_DIST[:, None], w, axis=1)
    return rho, np.full_like(rho, -H_S)


def _image_of(rho: np.ndarray, z: np.ndarray) -> RangeImage:
    """The range image whose cells lie at (rho, z) (rho 0 = empty); every row's cells must share
    one elevation, that of ``ROW_DIST`` on the road."""
    el = np.arctan2(-H_S, ROW_DIST)
    valid = rho > 0
    assert np.allclose(z[valid], (rho * np.tan(el)[:, None])[valid])
    ranges = np.where(valid, np.hypot(rho, z), 0.0).astype(np.float32)
    return RangeImage(
        ranges, el, np.flatnonzero(ranges.reshape(-1)), "native", one_point_per_pixel=True
    )


def _dip(rho: np.ndarray, z: np.ndarray, rows: slice, depth: float) -> None:
    """Lower the road by ``depth`` in ``rows`` (cells stay on their rays)."""
    scale = (H_S + depth) / H_S
    rho[rows] *= scale
    z[rows] = -(H_S + depth)


def _dip_street() -> tuple[np.ndarray, np.ndarray]:
    """The road dips 0.07 m from row 2 on; columns 15-20 see nothing above row 2, so their
    columns cannot confirm the dip (no surface above, 0.07 m is beyond the 0.05 m base band)."""
    rho, z = _road_rows()
    _dip(rho, z, slice(0, 3), 0.07)
    rho[:2, 15:21] = 0.0
    z[:2, 15:21] = 0.0
    return rho, z


def test_row_neighbours_take_ground_the_columns_cannot_confirm():
    rho, z = _dip_street()
    image = _image_of(rho, z)
    off = column_ground(image, neighbour_px=0)
    on = column_ground(image, neighbour_px=10)
    assert off[2, :15].all() and off[2, 21:].all()  # the columns confirm the dip from above
    assert not off[2, 15:21].any()
    assert on[2, 15:21].all()  # row 2 holds the same road 1-6 columns away
    assert np.array_equal(on[3:], off[3:]) and on[3:].all()
    # reach: with a reach of 3 columns only those within 3 of a column-taken cell
    near = column_ground(image, neighbour_px=3)
    assert near[2, 15:18].all() and near[2, 18:21].all()
    assert not column_ground(image, neighbour_px=2)[2, 17:19].any()


def test_row_neighbours_keep_the_foot_of_what_stands_on_the_cell():
    rho, z = _dip_street()
    # something standing on the cells of row 2, columns 15-20: row 1 hits its face 0.1 m farther
    # and about 0.3 m higher (a face leaning back at about 72 deg)
    el1 = np.arctan2(-H_S, ROW_DIST[1])
    rho[1, 15:21] = rho[2, 15:21] + 0.1
    z[1, 15:21] = rho[1, 15:21] * np.tan(el1)
    rise = np.degrees(np.arctan2(z[1, 15:21] - z[2, 15:21], 0.1))
    assert (rise > 60).all() and (rise < 80).all()
    image = _image_of(rho, z)
    assert not column_ground(image)[2, 15:21].any()  # a foot at foot_deg 30
    assert column_ground(image, foot_deg=85.0)[2, 15:21].all()  # not steep enough for 85 deg


def test_row_neighbours_do_not_carry_the_ground_along_the_face_of_an_object():
    # columns 15-20: rows 3 and 2 hit the vertical side of an object 10 m out, its top row at
    # the road's height beside it (10.2 m out in row 2), with far background above it (the top
    # outline of a car's side: no foot above it, so only the cell below shows the face)
    rho, z = _road_rows()
    el = np.arctan2(-H_S, ROW_DIST)
    for r, d in ((3, 10.0), (2, 10.0), (1, 30.0), (0, 30.0)):
        rho[r, 15:21] = d
        z[r, 15:21] = d * np.tan(el[r])
    image = _image_of(rho, z)
    assert abs(z[2, 15] - z[2, 14]) < 0.08 and abs(rho[2, 15] - rho[2, 14]) < 1.0  # a row hit
    assert not column_ground(image, neighbour_px=0)[2, 15:21].any()  # the columns refuse it
    mask, held = _held(image)
    assert not mask[2, 15:21].any() and not held[2, 15:21].any()  # on a face: an object's
    assert mask[2, :15].all() and mask[2, 21:].all()
    assert column_ground(image, face_deg=90.0)[2, 15:21].all()  # without the face test: ground


def test_row_neighbours_keep_ground_under_a_near_occluder():
    rho, z = _dip_street()
    el1 = np.arctan2(-H_S, ROW_DIST[1])
    for behind, kept in ((1.0, True), (3.0, False)):
        r2, z2 = rho.copy(), z.copy()
        r2[1, 15:21] = rho[2, 15:21] - behind  # a car body above the cell, nearer by `behind`
        z2[1, 15:21] = r2[1, 15:21] * np.tan(el1)
        got = column_ground(_image_of(r2, z2), under_m=2.0)[2, 15:21]
        assert (not got.any()) if kept else got.all()


# ---- step 7: points hidden behind their pixel's nearest point --------------------------------


def _hidden_scan() -> tuple[RangeImage, np.ndarray, np.ndarray]:
    """Two rows of road 1.73 m below the sensor, 20 columns, one point per pixel; pixel (1, 10)
    holds an object's point 2 m nearer and, behind it, a road point and a point 0.5 m above the
    road (both hidden). Returns the image (ring projection: several points per pixel), the
    points and the mask of a remover that took every road pixel."""
    el = np.array([-0.15, -0.2])
    h, w = 2, 20
    road = H_S / np.sin(-el)  # range of the road per row
    ranges = np.repeat(road[:, None], w, axis=1).astype(np.float32)
    ranges[1, 10] = road[1] - 2.0
    az = np.pi - (np.arange(w) + 0.5) * (2 * np.pi / w)

    def point(r: int, c: int, d: float, dz: float = 0.0) -> list[float]:
        rho = d * np.cos(el[r])
        return [rho * np.cos(az[c]), rho * np.sin(az[c]), d * np.sin(el[r]) + dz]

    pts = [point(r, c, ranges[r, c]) for r in range(h) for c in range(w)]
    pix = list(range(h * w))
    pts += [point(1, 10, road[1]), point(1, 10, road[1], dz=0.5)]
    pix += [w + 10, w + 10]
    points = np.array(pts, dtype=np.float32)
    counts = np.bincount(pix, minlength=h * w).reshape(h, w).astype(np.int32)
    image = RangeImage(ranges, el, np.array(pix, dtype=np.int64), "rings", counts)
    mask = np.ones((h, w), dtype=bool)
    mask[1, 10] = False
    return image, points, mask


def test_step_7_takes_a_hidden_road_point_and_keeps_the_object_and_a_raised_point():
    image, points, mask = _hidden_scan()
    got, clustered = ColumnGround().point_ground(image, points, mask)
    n = mask.size
    assert got[:n].tolist() == mask.reshape(-1).tolist()  # the pixels' own points
    assert got[n:].tolist() == [True, False]  # the road point behind the object; not 0.5 m up
    # the image the clusterers see, made in the same pass, is the generic one of that decision
    want = leave_pixels(image, mask, got)
    assert np.array_equal(clustered.point_pixel, want.point_pixel)
    assert np.array_equal(clustered.point_counts(), want.point_counts())
    # off, or on a sensor's own image (one point per pixel): every point takes its pixel's
    assert ColumnGround(hidden_points=False).point_ground(image, points, mask) is None
    native = RangeImage(
        image.ranges, image.elevation, np.arange(n), "native", one_point_per_pixel=True
    )
    assert ColumnGround().point_ground(native, points[:n], mask) is None
    # the row test: no taken pixel within reach of the point, nothing taken
    far = mask.copy()
    far[1, :] = False
    got, clustered = ColumnGround().point_ground(image, points, far)
    assert not got[n:].any() and clustered is image


def _step_7_reference(
    image: RangeImage, points: np.ndarray, mask: np.ndarray, reach: int = 10, band: float = 0.08
) -> np.ndarray:
    """Step 7 as the module docstring states it, point by point: a point takes its pixel's
    decision, unless it lies more than 1 mm behind its pixel's range in a pixel not ground and a
    ground pixel of its row at most ``reach`` columns away is within 1 m of its horizontal range
    and ``band`` of its height (that pixel's geometry as :func:`pixel_geometry` gives it)."""
    from flic_cli.ground.column import pixel_geometry

    rho_img, z_img, _, _ = pixel_geometry(image)
    w = image.shape[1]
    pix = image.point_pixel
    flat = mask.reshape(-1)
    out = np.zeros(pix.size, dtype=bool)
    has = pix >= 0
    out[has] = flat[pix[has]]
    xyz = points[:, :3].astype(np.float64)
    dist = np.sqrt((xyz**2).sum(axis=1))
    rng = image.ranges.reshape(-1).astype(np.float64)
    for i in np.flatnonzero(has & ~out):
        p = pix[i]
        if dist[i] <= rng[p] + 1e-3:
            continue
        r, c = divmod(int(p), w)
        cols = slice(max(c - reach, 0), c + reach + 1)
        rho = np.hypot(xyz[i, 0], xyz[i, 1])
        near = (np.abs(rho_img[r, cols] - rho) <= 1.0) & (
            np.abs(z_img[r, cols] - xyz[i, 2]) <= band
        )
        out[i] = bool((mask[r, cols] & near).any())
    return out


def _check_step_7(image: RangeImage, points: np.ndarray, mask: np.ndarray) -> None:
    """``ColumnGround.point_ground`` equals the reference, and the image it returns is the
    generic one of its decision (:func:`leave_pixels`)."""
    got, clustered = ColumnGround().point_ground(image, points, mask)
    assert np.array_equal(got, _step_7_reference(image, points, mask))
    want = leave_pixels(image, mask, got)
    assert np.array_equal(clustered.point_pixel, want.point_pixel)
    assert np.array_equal(clustered.point_counts(), want.point_counts())


@pytest.mark.slow
def test_step_7_equals_the_plain_reference_on_the_shared_frames(kitti_root):
    from flic_cli.config import load_config
    from flic_cli.runs.pipeline import prepare

    cfg = load_config()
    ds = open_dataset(kitti_root)
    for ref in ds.refs()[1::12]:
        prep = prepare(ds.load(ref), "ground", cfg.projection)
        _check_step_7(prep.image, prep.points, ColumnGround().extract(prep.image, prep.points).mask)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_step_7_equals_the_plain_reference_on_random_scans(seed):
    """Random points at a few ranges and heights, in 6 spherical bins x 64 columns, so that most
    pixels hold several points and some points fall outside the field of view (no pixel); with a
    random mask, and with the column remover's own (the projected scans of the shared frames,
    ring projection, are the test above)."""
    from flic_cli.projection import project_points

    rng = np.random.default_rng(seed)
    n = int(rng.integers(50, 3000))
    az = rng.uniform(-np.pi, np.pi, n)
    rho = rng.choice([4.0, 4.5, 8.0, 8.3, 20.0], n) + rng.normal(0.0, 0.3, n)
    z = rng.choice([-H_S, -H_S + 0.05, -1.0, 0.5], n) + rng.normal(0.0, 0.02, n)
    pts = np.stack([rho * np.cos(az), rho * np.sin(az), z], axis=1).astype(np.float32)
    image = project_points(
        pts, width=64, mode="spherical", rows=6, fov_up_deg=5.0, fov_down_deg=-20.0
    )
    _check_step_7(image, pts, rng.random(image.shape) < 0.5)
    _check_step_7(image, pts, ColumnGround().extract(image, pts).mask)


def test_the_clusterers_leave_out_the_points_taken_behind_a_pixel():
    from flic_cli.methods.dbscan import Dbscan
    from flic_cli.methods.flic import Flic

    image, points, mask = _hidden_scan()
    ground = GroundStep.from_mask(image, mask)  # a remover without step 7
    assert ground.image is image and ground.decided is None
    assert ground.on_ground.tolist() == mask.reshape(-1)[image.point_pixel].tolist()

    on_ground, clustered = ColumnGround().point_ground(image, points, mask)
    ground = GroundStep(mask, clustered, on_ground)
    n = mask.size
    assert ground.on_ground[n:].tolist() == [True, False]
    assert ground.image.point_pixel[n] == -1  # the hidden road point left its pixel
    assert ground.image.point_pixel[n + 1] == 20 + 10
    assert ground.image.point_counts()[1, 10] == 2 and image.point_counts()[1, 10] == 3
    # every clusterer gives it no label; the pixel's other points keep theirs
    for backend in ("numba", "scipy"):
        flic = Flic(min_size=1, backend=backend).segment(ground.image, points, ground)
        assert flic[n] == 0 and flic[20 + 10] > 0 and flic[n + 1] == flic[20 + 10]
    dbscan = Dbscan(eps_m=3.0, min_samples=1, min_size=1).segment(ground.image, points, ground)
    assert dbscan[n] == 0 and dbscan[20 + 10] > 0


# ---- the pixels' geometry on projected scans ---------------------------------------------------


def _projected_road(seed: int = 0) -> tuple[RangeImage, np.ndarray]:
    """A flat road 1.73 m below the sensor, 4-40 m out, as random points projected into 32
    uniform elevation bins: a point's elevation is anywhere within its bin, so its height is up
    to half a bin (0.44 deg, 30 cm at 40 m) from the one its row's elevation gives."""
    from flic_cli.projection import project_points

    rng = np.random.default_rng(seed)
    n = 200_000
    rho = np.sqrt(rng.uniform(4.0**2, 40.0**2, n))
    az = rng.uniform(-np.pi, np.pi, n)
    pts = np.stack([rho * np.cos(az), rho * np.sin(az), np.full(n, -H_S)], axis=1)
    pts = pts.astype(np.float32)
    return project_points(pts, width=512, mode="spherical", rows=32), pts


def test_pixels_of_a_projected_scan_lie_at_their_nearest_point():
    from flic_cli.ground.column import pixel_geometry

    image, pts = _projected_road()
    rho, z, up_rho, up_z = pixel_geometry(image)
    # the nearest point of every pixel, by brute force
    d = np.linalg.norm(pts.astype(np.float64), axis=1)
    order = np.lexsort((d, image.point_pixel))
    pix = image.point_pixel[order]
    first = order[np.r_[True, pix[1:] != pix[:-1]]]
    first = first[image.point_pixel[first] >= 0]
    flat = image.point_pixel[first]
    want_rho = np.zeros(image.ranges.size, np.float32)
    want_z = np.zeros(image.ranges.size, np.float32)
    want_rho[flat] = np.hypot(pts[first, 0].astype(np.float64), pts[first, 1])
    want_z[flat] = pts[first, 2]
    assert np.allclose(rho.reshape(-1), want_rho, atol=1e-5)
    assert np.array_equal(z.reshape(-1), want_z)
    assert np.array_equal(rho > 0, image.ranges > 0)
    # the next valid cell above
    r, c = 20, 100
    above = [k for k in range(r - 1, -1, -1) if rho[k, c] > 0]
    assert up_rho[r, c] == (rho[above[0], c] if above else 0.0)
    assert up_z[r, c] == (z[above[0], c] if above else 0.0)
    # as on a sensor's own image: the row's elevation
    own = pixel_geometry(image, exact=False)
    assert np.array_equal(
        own[1], image.ranges * np.sin(image.elevation).astype(np.float32)[:, None]
    )


def test_a_projected_road_is_ground_at_its_points_heights():
    image, pts = _projected_road()
    valid = image.ranges > 0
    at_points = ColumnGround().extract(image, pts).mask
    at_rows = ColumnGround(point_heights=False).extract(image, pts).mask
    assert np.array_equal(column_ground(image), at_points)
    assert np.array_equal(column_ground(image, point_heights=False), at_rows)
    assert at_points[valid].mean() > 0.999
    assert at_rows[valid].mean() < at_points[valid].mean()


# ---- step 8: cells stood on are held out and join what stands on them --------------------------


def _foot_street() -> tuple[np.ndarray, np.ndarray]:
    """The dip street of step 6 with something standing on row 2, columns 15-20: row 1 hits its
    face 0.1 m farther and about 0.3 m higher."""
    rho, z = _dip_street()
    rho[1, 15:21] = rho[2, 15:21] + 0.1
    z[1, 15:21] = rho[1, 15:21] * np.tan(np.arctan2(-H_S, ROW_DIST[1]))
    return rho, z


def _held(image: RangeImage, **kw) -> tuple[np.ndarray, np.ndarray]:
    held = np.zeros(image.shape, dtype=bool)
    return column_ground(image, held=held, **kw), held


def test_the_foot_of_what_stands_on_the_ground_is_held_not_taken():
    image = _image_of(*_foot_street())
    mask, held = _held(image)
    assert held[2, 15:21].all() and not mask[2, 15:21].any()
    assert held.sum() == 6  # nothing else is stood on
    mask, held = _held(image, foot_deg=85.0)  # not a foot at 85 deg: ground, nothing held
    assert mask[2, 15:21].all() and not held.any()
    remover = ColumnGround()
    assert np.array_equal(remover.extract(image).held, _held(image)[1])
    assert ColumnGround(hold_feet=False).extract(image).held is None


def _held_property(image: RangeImage, **kw) -> None:
    """Held cells are exactly what step 6 takes once the foot and under test is off (the face
    test, which reads the decision of the rows below, off in both)."""
    kw = {"face_deg": 90.0, **kw}
    mask, held = _held(image, **kw)
    off = column_ground(image, **{**kw, "foot_deg": 89.999, "under_m": 0.0})
    assert not (mask & held).any()
    assert np.array_equal(mask | held, off)


def test_held_cells_are_the_cells_step_6_refuses_on_synthetic_streets():
    person = _person(9.0, 5.0, -1.58, 2)
    scenes = [_scene(STREET, _car(20.0, -1.5, -H_S, 1)), _scene(STREET, [], [person])]
    for seed, scene in enumerate(scenes):
        image, _, _ = _image(scene, seed)
        _held_property(image)
        _held_property(image, neighbour_px=30, neighbour_band_m=0.2)


@settings(max_examples=60, deadline=None)
@given(RANDOM_RANGES)
def test_held_cells_are_the_cells_step_6_refuses_on_random_images(ranges):
    _held_property(_random_image(ranges), neighbour_band_m=1.0)


def _column_image() -> tuple[RangeImage, np.ndarray]:
    """One column of 5 rows 1 deg apart at 10 m (0.17 m between neighbours), one point per
    pixel, and an empty held mask."""
    el = np.radians([0.0, -1.0, -2.0, -3.0, -4.0])
    ranges = np.full((5, 1), 10.0, dtype=np.float32)
    counts = np.ones((5, 1), dtype=np.int32)
    image = RangeImage(ranges, el, np.arange(5), "native", counts, one_point_per_pixel=True)
    return image, np.zeros((5, 1), dtype=bool)


def test_a_held_foot_takes_the_cell_standing_on_it():
    image = _image_of(*_foot_street())  # 40 columns; row 1 stands on row 2, columns 15-20
    ground = ColumnGround().extract(image)
    cols = np.arange(15, 21)
    attached = ground.attached
    assert sorted(attached.tolist()) == [[80 + c, 40 + c, 1] for c in cols]  # 0.3 m apart
    assert np.array_equal(np.sort(attached[:, 0]), np.flatnonzero(ground.held))
    assert (ColumnGround(attach_m=0.2).extract(image).attached[:, 1] == -1).all()
    no_hold = ColumnGround(hold_feet=False).extract(image)
    assert no_hold.held is None and no_hold.attached is None


def test_held_cells_standing_on_ground_or_held_cells():
    from flic_cli.ground.column import _attached

    # one column of 5 rows (w = 1); the kernel lists held cells from the bottom row up
    held = np.array([False, False, True, True, True])
    ground = np.zeros(5, dtype=bool)
    counts = np.array([1, 1, 2, 3, 1], dtype=np.int32)
    cells = np.array([4, 3, 2])
    standers = np.array([3, 2, 1])  # a chain: 4 under 3 under 2, which stands on 1
    got = _attached(cells, standers, ground, held, counts, False, 1)
    assert got.tolist() == [[2, 1, 2], [3, 1, 3], [4, 1, 1]]
    ground[1] = True  # standing on ground: none, down the chain
    assert _attached(cells, standers, ground, held, counts, False, 1)[:, 1].tolist() == [-1, -1, -1]
    ground[1] = False
    standers = np.array([3, -1, 1])  # row 3 too far from row 2: none for rows 3 and 4
    assert _attached(cells, standers, ground, held, counts, False, 1)[:, 1].tolist() == [1, -1, -1]


def _attached(
    image: RangeImage, held: np.ndarray, rows: list[tuple[int, int]] | None
) -> GroundStep:
    """A ground step on ``image`` with nothing ground, the cells ``held`` held and attached as
    ``rows``, ``(pixel, target)`` (one point each; None: held without attachments, as a plain
    mask of pixels left out)."""
    none = np.zeros(image.shape, dtype=bool)
    if rows is None:
        return GroundStep.from_mask(image, held)
    attached = np.array([(p, t, 1) for p, t in rows], dtype=np.int64).reshape(-1, 3)
    return GroundStep(none, image, held=held, attached=attached)


@pytest.mark.parametrize("kind", ["flic", "flic-scipy", "bridge", "bogoslavskyi", "dbscan"])
def test_held_points_count_towards_the_minimum_size_and_link_nothing(kind):
    from flic_cli.methods import Bogoslavskyi, Bridge, Dbscan, Flic

    def method(min_size: int):
        return {
            "flic": Flic(min_size=min_size),
            "flic-scipy": Flic(min_size=min_size, backend="scipy"),
            "bridge": Bridge(min_size=min_size),
            "bogoslavskyi": Bogoslavskyi(min_size=min_size, angle_deg=1.0),
            "dbscan": Dbscan(min_size=min_size, eps_m=0.3, min_samples=1),
        }[kind]

    image, held = _column_image()
    points = image.to_points()[image.point_pixel]
    held[3:] = True
    with_held = _attached(image, held, [(3, 2), (4, 2)])
    assert method(5).segment(image, points, with_held).tolist() == [1, 1, 1, 1, 1]
    assert method(6).segment(image, points, with_held).tolist() == [0, 0, 0, 0, 0]
    # without the attachment, the held cells are left out and the rest is too small for 5
    bare = _attached(image, held, None)
    assert method(5).segment(image, points, bare).tolist() == [0, 0, 0, 0, 0]
    # a held cell between two clusters links nothing: rows 0-1 and 3-4 stay apart
    held = np.zeros_like(held)
    held[2] = True
    ranges = image.ranges.copy()
    ranges[1] = 30.0  # row 1 far behind: row 2 has no cell within 0.5 m above it
    far = RangeImage(
        ranges,
        image.elevation,
        np.arange(5),
        "native",
        image.point_counts(),
        one_point_per_pixel=True,
    )
    points = far.to_points()[far.point_pixel]
    got = method(1).segment(far, points, _attached(far, held, [(2, -1)])).tolist()
    assert got[2] == 0 and got[3] == got[4] and len({got[0], got[1], got[3]}) == 3


@pytest.mark.slow
@pytest.mark.parametrize(
    "name", ["bogoslavskyi", "flic0", "flic14n", "flic0-scipy", "bridge", "dbscan"]
)
def test_held_points_take_the_cluster_standing_on_them(kitti_root, name):
    from flic_cli.config import load_config
    from flic_cli.ground.base import pixel_owners
    from flic_cli.runs.pipeline import build_segmenter, cluster_ground, prepare

    cfg = load_config()
    seg = build_segmenter(cfg, name, "ground", "column")
    ds = open_dataset(kitti_root)
    prep = prepare(ds.load(ds.refs()[0]), "ground", cfg.projection)
    ground = seg.remover.extract(prep.image, prep.points)
    assert ground.held.any() and not (ground.held & ground.mask).any()
    attached = ground.attached
    assert np.array_equal(np.sort(attached[:, 0]), np.flatnonzero(ground.held))
    # a held pixel counts the points that stay in it (not those step 7 took as ground)
    counts = ground.image.point_counts().reshape(-1)
    assert np.array_equal(attached[:, 2], counts[attached[:, 0]])
    assert (attached[:, 2] < prep.image.point_counts().reshape(-1)[attached[:, 0]]).any()
    target = np.full(ground.held.size, -1)
    target[attached[:, 0]] = attached[:, 1]
    assert not ground.held.reshape(-1)[attached[attached[:, 1] >= 0, 1]].any()
    assert not ground.mask.reshape(-1)[attached[attached[:, 1] >= 0, 1]].any()
    labels = cluster_ground(seg.method, prep.points, ground)
    pix = ground.image.point_pixel
    held_pts = np.flatnonzero((pix >= 0) & ground.held.reshape(-1)[np.maximum(pix, 0)])
    assert not ground.on_ground[held_pts].any()  # held points are not ground
    t = target[pix[held_pts]]
    assert (t < 0).any() and (labels[held_pts][t >= 0] > 0).any()
    assert not labels[held_pts][t < 0].any()
    if name == "dbscan":  # a point of the target pixel in the same cluster
        pairs = set(zip(pix.tolist(), labels.tolist(), strict=True))
        got = labels[held_pts][t >= 0]
        assert all(lab == 0 or (q, lab) in pairs for q, lab in zip(t[t >= 0], got, strict=True))
    else:  # every point of a pixel has the pixel's label
        owner = pixel_owners(ground.image, prep.points)
        assert np.array_equal(labels[held_pts][t >= 0], labels[owner[t[t >= 0]]])
