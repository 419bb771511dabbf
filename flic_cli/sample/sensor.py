"""The sensor: a Velodyne HDL-64E-like ray caster with noise, dropouts and the recording car.

:data:`HDL64_PITCH_DEG` models the HDL-64E's two laser blocks; :func:`cast` intersects a grid of
rays (beam pitches x column azimuths) with a :class:`~flic_cli.sample.scene.Scene` (first hit,
vectorised over rays) and, unless ``noise=False``, adds range noise, random dropouts, dark-paint
dropouts on some cars (growing with range), window glass, and grazing-angle dropouts on the ground
beyond 15 m (dark asphalt: 5 % of the returns left at 27 m). Occlusions and moving objects come out
of the geometry. :data:`EGO_VEHICLE` is the Moosmann recording car, which hides the lower beams
ahead and behind.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flic_cli.sample.scene import REMISSION, ROAD, SIDEWALK, TERRAIN, Box, Ground, Scene

__all__ = [
    "DEFAULT_SENSOR",
    "EGO_VEHICLE",
    "HDL64_PITCH_DEG",
    "MAX_RANGE_M",
    "MOOSMANN_HEIGHT",
    "MOOSMANN_WIDTH",
    "SENSOR_PROFILES",
    "SensorProfile",
    "cast",
    "cast_full",
    "kitti_azimuths",
    "moosmann_azimuths",
]
#: Pitch of every beam in degrees, positive = downward, row 0 = top beam (64 values).
#: The real Moosmann ``img.cfg`` spans -1.9367 .. 24.9992 deg. The HDL-64E has two laser blocks:
#: the upper block (rows 0..31) is modelled as linear from -1.9367 to 8.5 deg (about 1/3 deg
#: spacing), the lower block (rows 32..63) as linear from 8.87 to 24.9992 deg (about 1/2 deg).
HDL64_PITCH_DEG: np.ndarray = np.concatenate(
    [np.linspace(-1.9367, 8.5, 32), np.linspace(8.87, 24.9992, 32)]
)
HDL64_PITCH_DEG.setflags(write=False)

# ---------------------------------------------------------------------------------------------
# Sensor profiles: other sensors' beam tables and resolutions (``flic sample --sensor NAME``)
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SensorProfile:
    """A spinning lidar as the ray caster models it: one beam per image row, one azimuth per
    column, all beams of a column firing at the column's azimuth from the sensor's origin.

    What is left out, for every profile: the beams' azimuth offsets (Velodyne's ``rot_correction``,
    Ouster's ``beam_azimuth_angles``: the image is the destaggered one, every beam of a column at
    the column's azimuth), the beams' origin offsets (Velodyne's focal distance and vertical
    offsets, Ouster's ``lidar_origin_to_beam_origin_mm``, 1-3 cm), the firing time within a
    revolution (the street is frozen during a sweep: no rolling shutter), intensity models and
    second returns. The noise and dropout model of :func:`cast` is the same for every sensor.

    Attributes
    ----------
    name : the ``--sensor`` name.
    title : the sensor, in words.
    pitch_deg : (H,) beam pitch in degrees, positive = downward, top beam first (sorted).
    width : columns per revolution at 10 Hz.
    source : where the beam table and the column count come from.
    """

    name: str
    title: str
    pitch_deg: np.ndarray
    width: int
    source: str

    @property
    def beams(self) -> int:
        """Number of beams (image rows)."""
        return int(self.pitch_deg.size)

    @property
    def vertical_fov_deg(self) -> tuple[float, float]:
        """(lowest, highest) beam elevation, degrees (positive = up)."""
        return float(-self.pitch_deg[-1]), float(-self.pitch_deg[0])

    @property
    def beam_spacing_deg(self) -> np.ndarray:
        """(H - 1,) elevation step between adjacent rows, degrees."""
        return np.diff(self.pitch_deg)

    @property
    def column_step_deg(self) -> float:
        """Azimuth step between adjacent columns, degrees."""
        return 360.0 / self.width


def _profile(
    name: str, title: str, elevation_deg: list[float], width: int, source: str
) -> SensorProfile:
    """A profile from elevations in degrees (positive = up, any order), sorted top beam first."""
    pitch = np.sort(-np.asarray(elevation_deg, dtype=np.float64))
    pitch.setflags(write=False)
    if np.unique(pitch).size != pitch.size:
        raise ValueError(f"{name}: two beams at the same elevation")
    return SensorProfile(name, title, pitch, width, source)


#: Velodyne VLP-32C elevations in firing order (laser id 0..31), degrees: the table of the
#: VLP-32C user manual (also velodyne-decoder's default calibration), -25 .. +15 deg, dense
#: (1/3 deg) around the horizon, sparse (up to 8 deg) towards the ends.
_VLP32C_ELEVATION_DEG = [
    -25.0, -1.0, -1.667, -15.639, -11.31, 0.0, -0.667, -8.843,
    -7.254, 0.333, -0.333, -6.148, -5.333, 1.333, 0.667, -4.0,
    -4.667, 1.667, 1.0, -3.667, -3.333, 3.333, 2.333, -2.667,
    -3.0, 7.0, 4.667, -2.333, -2.0, 15.0, 10.333, -1.333,
]  # fmt: skip

#: Ouster OS-1-64: ``beam_altitude_angles`` of a real unit (the metadata of ouster-sdk's test
#: recording ``OS-1-64_1024x10_fw20``, BSD-3-Clause; docs/specification.md, section 4),
#: +16.46 .. -16.75 deg, gaps alternating about 0.53 and 0.48 deg.
_OS1_64_ELEVATION_DEG = [
    16.46, 15.88, 15.32, 14.8, 14.29, 13.71, 13.17, 12.63, 12.15, 11.58, 11.05, 10.52, 10.05,
    9.49, 8.95, 8.43, 7.95, 7.41, 6.88, 6.34, 5.87, 5.33, 4.8, 4.27, 3.79, 3.26, 2.72, 2.19,
    1.71, 1.18, 0.65, 0.12, -0.36, -0.9, -1.43, -1.96, -2.44, -2.97, -3.51, -4.04, -4.52, -5.05,
    -5.58, -6.12, -6.61, -7.13, -7.67, -8.22, -8.7, -9.22, -9.76, -10.3, -10.8, -11.33, -11.86,
    -12.43, -12.91, -13.45, -14.0, -14.57, -15.07, -15.6, -16.17, -16.75,
]  # fmt: skip

#: Ouster OS-2-128: ``beam_altitude_angles`` of a real unit (ouster-sdk's test recording
#: ``OS-2-128-U1_v2.3.0_1024x10``, BSD-3-Clause), +10.76 .. -11.09 deg, gaps 0.14-0.20 deg.
_OS2_128_ELEVATION_DEG = [
    10.76, 10.58, 10.42, 10.24, 10.1, 9.93, 9.76, 9.57, 9.41, 9.24, 9.09, 8.91, 8.75, 8.57,
    8.41, 8.23, 8.08, 7.9, 7.74, 7.55, 7.39, 7.21, 7.03, 6.86, 6.7, 6.53, 6.35, 6.18, 6.02,
    5.83, 5.67, 5.5, 5.32, 5.14, 4.97, 4.81, 4.63, 4.46, 4.28, 4.11, 3.95, 3.76, 3.58, 3.43,
    3.24, 3.07, 2.9, 2.72, 2.55, 2.37, 2.21, 2.03, 1.87, 1.69, 1.51, 1.32, 1.16, 0.98, 0.81,
    0.63, 0.46, 0.29, 0.11, -0.05, -0.25, -0.42, -0.58, -0.76, -0.93, -1.11, -1.28, -1.45,
    -1.63, -1.81, -1.97, -2.16, -2.32, -2.5, -2.68, -2.85, -3.02, -3.19, -3.37, -3.55, -3.73,
    -3.9, -4.07, -4.25, -4.4, -4.58, -4.75, -4.94, -5.11, -5.28, -5.46, -5.64, -5.8, -5.96,
    -6.15, -6.32, -6.49, -6.66, -6.84, -7.0, -7.17, -7.35, -7.51, -7.69, -7.86, -8.04, -8.22,
    -8.38, -8.55, -8.72, -8.89, -9.06, -9.23, -9.4, -9.57, -9.74, -9.91, -10.07, -10.24,
    -10.41, -10.58, -10.75, -10.92, -11.09,
]  # fmt: skip

#: The name of the sample's own sensor (the default of ``flic sample --sensor``).
DEFAULT_SENSOR = "hdl64e"

#: ``flic sample --sensor NAME``: every profile the sample can cast, by name.
SENSOR_PROFILES: dict[str, SensorProfile] = {
    p.name: p
    for p in (
        _profile(
            "vlp16",
            "Velodyne VLP-16",
            list(np.arange(-15.0, 15.5, 2.0)),
            1800,
            "VLP-16 user manual: 16 beams -15 .. +15 deg every 2 deg; 0.2 deg azimuth "
            "steps at 10 Hz (1800 columns)",
        ),
        _profile(
            "vlp32c",
            "Velodyne VLP-32C",
            _VLP32C_ELEVATION_DEG,
            1800,
            "VLP-32C user manual's elevation table (non-uniform, -25 .. +15 deg); 0.2 deg "
            "azimuth steps at 10 Hz (1800 columns)",
        ),
        _profile(
            "hdl32e",
            "Velodyne HDL-32E",
            list(-30.67 + np.arange(32) * 4.0 / 3.0),
            2170,
            "HDL-32E user manual: 32 beams -30.67 .. +10.67 deg every 4/3 deg; 694,292 "
            "points/s / 32 beams / 10 Hz = about 2170 columns",
        ),
        SensorProfile(
            "hdl64e",
            "Velodyne HDL-64E (the sample's own model)",
            HDL64_PITCH_DEG,
            2048,
            "the sample's HDL-64E model (HDL64_PITCH_DEG: two blocks, linear within each, "
            "+1.94 .. -25 deg) and KITTI's 2048 columns; an approximation of the real table",
        ),
        _profile(
            "os1-64",
            "Ouster OS1-64",
            _OS1_64_ELEVATION_DEG,
            1024,
            "beam_altitude_angles of a real OS-1-64 (ouster-sdk test data, "
            "OS-1-64_1024x10_fw20); lidar_mode 1024x10",
        ),
        _profile(
            "os1-128",
            "Ouster OS1-128",
            list(np.linspace(22.5, -22.5, 128)),
            2048,
            "approximation: the OS1 datasheet's 45 deg vertical field of view with uniform beam "
            "spacing (128 beams +22.5 .. -22.5 deg, 0.354 deg apart), no unit's calibration; "
            "lidar_mode 2048x10",
        ),
        _profile(
            "os2-128",
            "Ouster OS2-128",
            _OS2_128_ELEVATION_DEG,
            1024,
            "beam_altitude_angles of a real OS-2-128 (ouster-sdk test data, "
            "OS-2-128-U1_v2.3.0_1024x10); lidar_mode 1024x10",
        ),
    )
}


#: No return beyond this range (metres).
MAX_RANGE_M: float = 120.0

#: Moosmann range image size (columns, rows).
MOOSMANN_WIDTH: int = 870
MOOSMANN_HEIGHT: int = 64

#: Ground returns fade with range (grazing incidence on dark asphalt): full up to ``[0]`` metres,
#: then falling linearly to 5 % over ``[1]`` more metres.
_GRAZE_M = (15.0, 12.0)


#: The Moosmann recording car in its sensor frame, as the sensor sees it: a 4.5 x 1.8 m box from
#: 2.0 m ahead of the sensor to 2.5 m behind it, its top (roof, hood and trunk lumped) 0.5 m below
#: the sensor and its bottom 0.18 m above the road. Rays that hit it give no return (see
#: :func:`cast`): it hides the beams steeper than 14 deg looking ahead and 11 deg looking back
#: (10.6 deg past the rear corners); sideways even the lowest beam (25 deg) clears it.
EGO_VEHICLE: tuple[Box, ...] = (Box((-0.25, 0.0, -1.025), (2.25, 0.9, 0.525), 0.0, 0),)


def _wrap_angle(a: np.ndarray | float) -> np.ndarray | float:
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def _ray_window(
    corners_xy: np.ndarray,
    rho_min: float,
    z_lo: float,
    z_hi: float,
    elev: np.ndarray,
    az: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns whose rays can reach an object (conservative angular bounds).

    Parameters
    ----------
    corners_xy : (K, 2) points whose convex hull contains the object's footprint, metres.
    rho_min : horizontal distance from the sensor to the footprint, metres (0 = sensor inside).
    z_lo, z_hi : vertical extent of the object, metres.
    elev : (H,) ray elevations in radians; az : (W,) ray azimuths in radians.
    """
    rho = np.hypot(corners_xy[:, 0], corners_xy[:, 1])
    rho_max = float(rho.max())
    eps = 1e-6
    if rho_min <= 1e-9:
        cols = np.arange(az.size)
    else:
        centre = float(np.arctan2(corners_xy[:, 1].mean(), corners_xy[:, 0].mean()))
        rel = _wrap_angle(np.arctan2(corners_xy[:, 1], corners_xy[:, 0]) - centre)
        rel_az = _wrap_angle(az - centre)
        cols = np.flatnonzero((rel_az >= rel.min() - eps) & (rel_az <= rel.max() + eps))
    near = max(rho_min, 1e-9)
    el_hi = np.arctan2(z_hi, near if z_hi > 0 else rho_max)
    el_lo = np.arctan2(z_lo, near if z_lo < 0 else rho_max)
    rows = np.flatnonzero((elev >= el_lo - eps) & (elev <= el_hi + eps))
    return rows, cols


def _safe(d: np.ndarray) -> np.ndarray:
    """Direction components with exact zeros nudged away (keeps the slab test free of NaNs)."""
    return np.where(np.abs(d) < 1e-12, 1e-12, d)


def _vehicle_hits(
    vehicle: tuple[Box, ...], dx: np.ndarray, dy: np.ndarray, dz: np.ndarray
) -> np.ndarray:
    """(H, W) bool: rays that hit a box of the recording vehicle (axis-aligned, sensor frame)."""
    hit = np.zeros(dx.shape, dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for b in vehicle:
            tnear = np.zeros(dx.shape)
            tfar = np.full(dx.shape, np.inf)
            for d, c, hw in zip((dx, dy, dz), b.center, b.half, strict=True):
                d = _safe(d)
                t1, t2 = (c - hw) / d, (c + hw) / d
                tnear = np.maximum(tnear, np.minimum(t1, t2))
                tfar = np.minimum(tfar, np.maximum(t1, t2))
            hit |= tnear <= tfar
    return hit


def _cast_ground(
    g: Ground, dx: np.ndarray, dy: np.ndarray, dz: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """First hit of every ray with the ground: road plane, raised sidewalk/terrain plane and the
    two kerb faces.

    Returns
    -------
    t : (H, W) float64 distance to the hit in metres, inf where the ray misses the ground.
    semantic : (H, W) uint16 road, sidewalk (also the kerb faces) or terrain; 0 where missed.
    """
    best_t = np.full(dx.shape, np.inf)
    sem = np.zeros(dx.shape, dtype=np.uint16)
    denom = dz - g.slope * dx
    y_r, y_l = g.road_y
    with np.errstate(divide="ignore", invalid="ignore"):
        for lift, on_road in ((0.0, True), (g.kerb_height, False)):
            t = np.where(denom < -1e-12, (-g.sensor_height + lift) / denom, np.inf)
            y = t * dy
            inside = (y > y_r) & (y < y_l)
            ok = np.isfinite(t) & (inside if on_road else ~inside)
            better = ok & (t < best_t)
            best_t[better] = t[better]
            if on_road:
                sem[better] = ROAD
            else:
                yo = y[better]
                sw = (yo > g.sidewalk_y[0]) & (yo < g.sidewalk_y[1])
                sem[better] = np.where(sw, SIDEWALK, TERRAIN)
        for y_k in (y_r, y_l):
            t = y_k / _safe(dy)
            z = t * dz
            zr = -g.sensor_height + g.slope * t * dx
            ok = (t > 0) & (z >= zr) & (z <= zr + g.kerb_height)
            better = ok & (t < best_t)
            best_t[better] = t[better]
            sem[better] = SIDEWALK
    return best_t, sem


def cast_full(
    scene: Scene,
    pitch_deg: np.ndarray,
    azimuths_rad: np.ndarray,
    rng: np.random.Generator | None,
    vehicle: tuple[Box, ...] = (),
    noise: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`cast` plus the remission (0..1) of every return, (H, W) float32."""
    pitch = np.asarray(pitch_deg, dtype=np.float64).reshape(-1)
    az = np.asarray(azimuths_rad, dtype=np.float64).reshape(-1)
    h, w = pitch.size, az.size
    elev = -np.radians(pitch)
    ce, se = np.cos(elev), np.sin(elev)
    dx = ce[:, None] * np.cos(az)[None, :]
    dy = ce[:, None] * np.sin(az)[None, :]
    dz = np.broadcast_to(se[:, None], (h, w))

    # --- ground ----------------------------------------------------------------------------------
    if scene.ground is None:
        best_t = np.full((h, w), np.inf)
        sem = np.zeros((h, w), dtype=np.uint16)
    else:
        best_t, sem = _cast_ground(scene.ground, dx, dy, dz)
    inst = np.zeros((h, w), dtype=np.uint16)
    rem = np.zeros((h, w))
    ground_hit = np.isfinite(best_t)
    rem[ground_hit] = np.vectorize(REMISSION.get, otypes=[float])(sem[ground_hit])
    # Far ground at grazing incidence returns less and less (dark asphalt).
    r_g = np.where(ground_hit, best_t, 0.0)
    p_ret = np.where(ground_hit, np.clip(1.0 - (r_g - _GRAZE_M[0]) / _GRAZE_M[1], 0.05, 1.0), 1.0)

    # --- boxes: slab test in the box's own frame ----------------------------------------------
    for b in scene.boxes:
        cx, cy, cz = b.center
        hx, hy, hz = b.half
        c, s = np.cos(b.yaw), np.sin(b.yaw)
        ox, oy = -(c * cx + s * cy), -(-s * cx + c * cy)  # sensor origin in the box frame
        oz = -cz
        lx = np.array([-hx, hx, hx, -hx])
        ly = np.array([-hy, -hy, hy, hy])
        corners = np.stack([cx + c * lx - s * ly, cy + s * lx + c * ly], axis=1)
        rho_min = float(np.hypot(ox - np.clip(ox, -hx, hx), oy - np.clip(oy, -hy, hy)))
        rows, cols = _ray_window(corners, rho_min, cz - hz, cz + hz, elev, az)
        if rows.size == 0 or cols.size == 0:
            continue
        ix = np.ix_(rows, cols)
        sdx, sdy, sdz = dx[ix], dy[ix], dz[ix]
        lx_d = _safe(c * sdx + s * sdy)
        ly_d = _safe(-s * sdx + c * sdy)
        lz_d = _safe(sdz)
        tx1, tx2 = (-hx - ox) / lx_d, (hx - ox) / lx_d
        ty1, ty2 = (-hy - oy) / ly_d, (hy - oy) / ly_d
        tz1, tz2 = (-hz - oz) / lz_d, (hz - oz) / lz_d
        txn, tyn, tzn = np.minimum(tx1, tx2), np.minimum(ty1, ty2), np.minimum(tz1, tz2)
        tnear = np.maximum(np.maximum(txn, tyn), tzn)
        tfar = np.minimum(
            np.minimum(np.maximum(tx1, tx2), np.maximum(ty1, ty2)), np.maximum(tz1, tz2)
        )
        sub_best = best_t[ix]
        hit = (tnear <= tfar) & (tnear > 0) & (tnear < sub_best)
        if not hit.any():
            continue
        pr = np.full(hit.shape, b.p_return)
        t_hit = tnear
        if b.facade:
            # Glazed windows on every vertical face. A ray through the glass returns from the room
            # behind it (a wall or a shelf at a depth fixed per window) or not at all. A shop's
            # ground floor is glazed from the pavement up, between narrow pillars.
            on_x_face = txn >= np.maximum(tyn, tzn)
            along = np.where(on_x_face, oy + tnear * ly_d, ox + tnear * lx_d)
            up = oz + tnear * lz_d + hz - 0.3  # height above the pavement
            bay = 2.4 if b.shopfront else 2.2
            a = along % bay
            pane = (a > 0.5) & (a < 1.7) & ((up % 3.0) > 0.9) & ((up % 3.0) < 2.4)
            if b.shopfront:
                pane |= (a > 0.45) & (up > 0.0) & (up < 2.8)
            pane &= tzn < np.maximum(txn, tyn)  # not on the roof
            window = np.floor(along / bay) * 31.0 + np.floor(up / 3.0)
            key = 12.9898 * hx + 78.233 * hy + 37.719 * hz
            depth = 1.5 + 4.0 * ((np.sin(window * 12.9898 + key) * 43758.5453) % 1.0)
            t_hit = np.where(pane, tnear + depth, tnear)
            pr = np.where(pane, 0.85, pr)
        sub_best[hit] = t_hit[hit]
        best_t[ix] = sub_best
        for arr, val in ((sem, b.semantic), (inst, b.instance), (rem, b.remission)):
            sub = arr[ix]
            sub[hit] = val
            arr[ix] = sub
        sub = p_ret[ix]
        sub[hit] = pr[hit]
        p_ret[ix] = sub

    # --- vertical cylinders: side surface and the two caps -------------------------------------
    for cy_ in scene.cylinders:
        cx, cy = cy_.center
        r = cy_.radius
        dist = float(np.hypot(cx, cy))
        ang = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)
        corners = np.stack(
            [cx + r * np.sqrt(2) * np.cos(ang), cy + r * np.sqrt(2) * np.sin(ang)], axis=1
        )
        near = dist - r if dist > 1.5 * r else 0.0  # close: no azimuth culling
        rows, cols = _ray_window(corners, near, cy_.z_min, cy_.z_max, elev, az)
        if rows.size == 0 or cols.size == 0:
            continue
        ix = np.ix_(rows, cols)
        sdx, sdy, sdz = dx[ix], dy[ix], dz[ix]
        # |o + t d|^2 = r^2 in the horizontal plane, with o = -centre.
        a = sdx**2 + sdy**2
        bq = -2.0 * (cx * sdx + cy * sdy)
        cq = dist**2 - r**2
        disc = bq**2 - 4.0 * a * cq
        with np.errstate(invalid="ignore", divide="ignore"):
            t_side = (-bq - np.sqrt(disc)) / (2.0 * a)
        z = t_side * sdz
        t_side = np.where(
            (disc >= 0) & (t_side > 0) & (z >= cy_.z_min) & (z <= cy_.z_max), t_side, np.inf
        )
        lz = _safe(sdz)
        t_cap = np.inf
        for zc in (cy_.z_min, cy_.z_max):
            tc = zc / lz
            inside = (tc > 0) & ((tc * sdx - cx) ** 2 + (tc * sdy - cy) ** 2 <= r * r)
            t_cap = np.minimum(t_cap, np.where(inside, tc, np.inf))
        t_hit = np.minimum(t_side, t_cap)
        sub_best = best_t[ix]
        hit = t_hit < sub_best
        if not hit.any():
            continue
        sub_best[hit] = t_hit[hit]
        best_t[ix] = sub_best
        for arr, val in (
            (sem, cy_.semantic),
            (inst, cy_.instance),
            (rem, cy_.remission),
            (p_ret, cy_.p_return),
        ):
            sub = arr[ix]
            sub[hit] = val
            arr[ix] = sub

    # --- sensor effects ------------------------------------------------------------------------
    valid = np.isfinite(best_t) & (best_t <= MAX_RANGE_M)
    if vehicle:
        valid &= ~_vehicle_hits(vehicle, dx, dy, dz)
    if not noise:
        ranges = np.where(valid, best_t, 0.0).astype(np.float32)
        sem = np.where(valid, sem, 0).astype(np.uint16)
        inst = np.where(valid, inst, 0).astype(np.uint16)
        return ranges, sem, inst, np.where(valid, rem, 0.0).astype(np.float32)
    if rng is None:
        rng = np.random.default_rng(0)
    u = rng.random((h, w))
    range_noise = rng.normal(0.0, 0.015, (h, w))
    global_drop = 0.015
    # Dark paint returns less and less with range (full up to 2 m, the base rate from 15 m on).
    dark = (rem < 0.12) & (p_ret < 1.0)
    p_ret = np.where(dark, 1.0 - (1.0 - p_ret) * np.clip((best_t - 2.0) / 13.0, 0.0, 1.0), p_ret)
    valid &= u < p_ret * (1.0 - global_drop)
    ranges = np.where(valid, best_t + range_noise, 0.0)
    valid &= ranges > 0
    ranges = np.where(valid, ranges, 0.0).astype(np.float32)
    sem = np.where(valid, sem, 0).astype(np.uint16)
    inst = np.where(valid, inst, 0).astype(np.uint16)
    rem = np.where(valid, np.clip(rem + rng.normal(0.0, 0.03, (h, w)), 0.0, 1.0), 0.0)
    return ranges, sem, inst, rem.astype(np.float32)


def cast(
    scene: Scene,
    pitch_deg: np.ndarray,
    azimuths_rad: np.ndarray,
    rng: np.random.Generator | None = None,
    vehicle: tuple[Box, ...] = (),
    *,
    noise: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cast a grid of rays from the sensor into the scene (first hit, vectorised over rays).

    Parameters
    ----------
    scene : the frame's scene (:func:`~flic_cli.sample.make_scene`,
        :func:`~flic_cli.sample.custom_scene`).
    pitch_deg : (H,) beam pitch in degrees, positive = downward, one per image row.
    azimuths_rad : (W,) column azimuth in radians (counter-clockwise from +x), one per column.
    rng : source of the sensor noise (range noise, dropouts); pass a seeded generator for
        reproducible output. None = ``np.random.default_rng(0)``. Unused without noise.
    vehicle : boxes of the recording car in the sensor frame (axis-aligned, e.g.
        :data:`EGO_VEHICLE`); a ray that hits one returns nothing. Default: none.
    noise : False for an ideal sensor: no range noise and no dropouts, every ray whose first hit
        lies within :data:`MAX_RANGE_M` returns its exact range (a window pane returns from the
        room behind it).

    Returns
    -------
    ranges : (H, W) float32
        Range in metres, 0 = no return (nothing within :data:`MAX_RANGE_M`, the ray hit the
        recording car, or a dropout).
    semantic : (H, W) uint16
        SemanticKITTI raw class id of every return, 0 where there is none.
    instance : (H, W) uint16
        Instance id of every return (things only), 0 elsewhere.
    """
    ranges, sem, inst, _ = cast_full(scene, pitch_deg, azimuths_rad, rng, vehicle, noise)
    return ranges, sem, inst


def moosmann_azimuths(width: int = MOOSMANN_WIDTH) -> np.ndarray:
    """(W,) azimuth of each column of a Moosmann image in radians: +180 - 360 * c / (W - 1) deg."""
    return np.radians(180.0 - 360.0 * np.arange(width) / (width - 1))


def kitti_azimuths(width: int = 2048) -> np.ndarray:
    """(W,) azimuths of one KITTI ring in scan order: ``2 pi (k + 0.5) / W``, radians."""
    return 2.0 * np.pi * (np.arange(width) + 0.5) / width
