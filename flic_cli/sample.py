"""A deterministic synthetic street and an HDL-64E-like ray caster: the embedded sample dataset.

The project ships no real lidar data (the Moosmann logs may not be redistributed, SemanticKITTI is a
large download). When the user gives no data path, the CLI writes this module's sample once into a
per-user cache folder and runs on it, so the main command of the README works out of the box.

The scene
---------
One straight one-way street per seed, in a world frame equal to the sensor frame of frame 0 (x
forward along the street, y left, z up, metres). The ego car drives down its single 3.8-4.2 m lane
at 10 m/s (1 m per frame at 10 Hz) and its sensor sits :data:`SENSOR_HEIGHT_M` above the road. The
road rises ahead with a gentle slope (1-2 deg: ``z = -1.73 + slope * x`` in the sensor frame); a
0.12 m kerb steps up to the sidewalks. Along the street:

- both parking strips are lined with parked cars, some bumper to bumper, most 1-2.5 m apart, now
  and then a 3.5-7 m driveway, and sometimes a van or truck on the left;
- on the right, a 3.4-4 m sidewalk with a cycle track along the kerb and shops: street trees
  (trunk + crown) every 4-7 m and, 1-3 m apart, lamps, sign posts, bollards, bins, planters,
  bicycles, scooters, utility cabinets and advertising columns along the kerb, benches, cafe tables
  and planters along the shop windows, and most of the 40-70 pedestrians (some in groups);
- on the left, a 2.2-2.8 m sidewalk with trees and sparser furniture, and front gardens (terrain)
  with hedges, fences and low walls in segments with gaps, shrubs and small trees;
- buildings in blocks of 1-4 segments whose frontage steps back and forth by 1-2 m, with 1.6-4.5 m
  alleys between blocks (through some, a building set further back); a building closes each end
  of the street;
- traffic: a car 6-9 m ahead keeping its distance to the ego car (often a second one ahead of it
  and one following the ego car) and 2-5 cyclists on the cycle track.

Every primitive is an axis-aligned or yaw-rotated box or a vertical cylinder with a SemanticKITTI
raw class id and, for things, an instance id (0 for stuff). A car is a body box, a thin roof slab
and six window pillars: rays pass through its windows and see what lies beyond, so its roof is
separated from its body by a gap of a few rows except at the pillars. Facades have glazed windows
(shops: glazed from the pavement up between narrow pillars); a ray through a window returns from
the room behind it, at a depth fixed per window, or not at all.

The sensor
----------
:data:`HDL64_PITCH_DEG` models the Velodyne HDL-64E's two laser blocks; :func:`cast` intersects a
grid of rays (beam pitches x column azimuths) with the scene (first hit, vectorised over rays) and
adds range noise, random dropouts, dark-paint dropouts on some cars (growing with range), window
glass, and grazing-angle dropouts on the ground beyond 15 m (dark asphalt: 5 % of the returns left
at 27 m). Occlusions and moving objects come out of the geometry.

The Moosmann recording car hides its sensor's lower beams: :data:`EGO_VEHICLE` (a 4.5 x 1.8 m box
whose top lies 0.5 m below the sensor, from 2 m ahead of it to 2.5 m behind) swallows the beams
steeper than 14 deg looking ahead and 11 deg looking back, about 9,300 of the 55,680 pixels of a
frame; rays that hit it give no return (range 0). Sideways even the lowest beam clears it. The
SemanticKITTI sequence is cast without it, like the real KITTI scans, which lose only a few
returns of their lowest beams behind the car: about 20 % of its points are ground.

Realism of the Moosmann log
---------------------------
Real Moosmann frames hold 40k-48k valid pixels of 870 x 64, 37k-43k of them left after ground
removal, and FLIC finds about 90-130 clusters in them. The default sample (seed 0, 20 frames) has
43.5k-44.1k valid pixels, 36.7k-39.8k (mean 38.3k) left after the paper's ground removal
(:func:`flic_cli.ground.paper_ground`), and FLIC with 0 Map Connections and the paper's ground
removal finds 41-58 clusters of at least 100 pixels (mean 47); seeds 1-3 give 34.8k-40.3k
non-ground pixels and 38-62 clusters. The cluster count falls short of the real logs': in an
870 x 64 image an object beyond about 15 m covers fewer than 100 pixels, and nearer objects hide one
another along the street, so adding objects (more furniture, trees, pedestrians, open space between
the parked cars) does not raise it beyond about 50-60. The KITTI scans hold about 124k points each.

Outputs
-------
:func:`write_sample` writes the same frames both as a SemanticKITTI sequence (points in the
sensor's scan order, so that :func:`flic_cli.range_image.project_points` recovers the 64 rings) and
as a Moosmann-style log (870 x 64 16-bit PNG range images + ``img.cfg``). :func:`ensure_sample`
writes the default sample into :func:`default_sample_dir` once and reuses it afterwards.
"""

from __future__ import annotations

import functools
import io
import os
import shutil
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

__all__ = [
    "EGO_VEHICLE",
    "HDL64_PITCH_DEG",
    "MAX_RANGE_M",
    "MOOSMANN_HEIGHT",
    "MOOSMANN_WIDTH",
    "SENSOR_HEIGHT_M",
    "Box",
    "Cylinder",
    "Ground",
    "SamplePaths",
    "Scene",
    "cast",
    "default_sample_dir",
    "ensure_sample",
    "kitti_azimuths",
    "make_scene",
    "moosmann_azimuths",
    "write_sample",
]

#: Pitch of every beam in degrees, positive = downward, row 0 = top beam (64 values).
#: The real Moosmann ``img.cfg`` spans -1.9367 .. 24.9992 deg. The HDL-64E has two laser blocks:
#: the upper block (rows 0..31) is modelled as linear from -1.9367 to 8.5 deg (about 1/3 deg
#: spacing), the lower block (rows 32..63) as linear from 8.87 to 24.9992 deg (about 1/2 deg).
HDL64_PITCH_DEG: np.ndarray = np.concatenate(
    [np.linspace(-1.9367, 8.5, 32), np.linspace(8.87, 24.9992, 32)]
)
HDL64_PITCH_DEG.setflags(write=False)

#: Height of the sensor above the road in metres.
SENSOR_HEIGHT_M: float = 1.73

#: No return beyond this range (metres).
MAX_RANGE_M: float = 120.0

#: Moosmann range image size (columns, rows).
MOOSMANN_WIDTH: int = 870
MOOSMANN_HEIGHT: int = 64

#: Ground returns fade with range (grazing incidence on dark asphalt): full up to ``[0]`` metres,
#: then falling linearly to 5 % over ``[1]`` more metres.
_GRAZE_M = (15.0, 12.0)

#: Frame rate of the sensor (Hz) and speed of the ego car (m/s).
_FPS = 10.0
_EGO_SPEED = 10.0

#: Base remission (0..1) per SemanticKITTI class.
_REMISSION = {
    40: 0.22,
    48: 0.30,
    72: 0.38,
    50: 0.28,
    51: 0.20,
    70: 0.45,
    71: 0.30,
    80: 0.55,
    10: 0.40,
    252: 0.40,
    30: 0.35,
    11: 0.30,
    15: 0.35,
    31: 0.30,
    18: 0.50,
    52: 0.35,
    81: 0.70,
    99: 0.45,
}

#: Classes that carry instance ids (SemanticKITTI "things").
_THING_CLASSES = frozenset({10, 11, 13, 15, 16, 18, 20, 30, 31, 32, *range(252, 260)})


# ---------------------------------------------------------------------------------------------
# Scene description
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Box:
    """A solid box, optionally rotated about the vertical axis.

    Attributes
    ----------
    center : (x, y, z) of the box centre, metres, sensor frame.
    half : half extents (along the box's own x, y and z axes), metres.
    yaw : rotation about z in radians (counter-clockwise, 0 = axis-aligned).
    semantic : SemanticKITTI raw class id.
    instance : instance id (0 for stuff).
    p_return : probability that a ray hitting the box gives a return (dark paint, foliage, fences).
    remission : reflectivity written to the KITTI ``.bin`` (0..1).
    facade : True for a building facade with glazed windows on its vertical faces: a ray through
        a window returns from the room behind it (at a depth fixed per window) with probability
        0.85, else not at all.
    shopfront : True for a facade whose ground floor is a row of shop windows, glazed from the
        pavement up between narrow pillars.
    """

    center: tuple[float, float, float]
    half: tuple[float, float, float]
    yaw: float
    semantic: int
    instance: int = 0
    p_return: float = 1.0
    remission: float = 0.3
    facade: bool = False
    shopfront: bool = False


@dataclass(frozen=True)
class Cylinder:
    """A solid vertical cylinder (pole, tree trunk, tree crown).

    Attributes
    ----------
    center : (x, y) of the axis, metres, sensor frame.
    radius : metres.
    z_min, z_max : bottom and top, metres, sensor frame.
    semantic, instance, p_return, remission : as for :class:`Box`.
    """

    center: tuple[float, float]
    radius: float
    z_min: float
    z_max: float
    semantic: int
    instance: int = 0
    p_return: float = 1.0
    remission: float = 0.3


@dataclass(frozen=True)
class Ground:
    """The ground: a sloped road between two kerbs, sidewalks, terrain beyond.

    The road surface is ``z = -sensor_height + slope * x`` (sensor frame, metres); sidewalks and
    terrain lie ``kerb_height`` higher.

    Attributes
    ----------
    slope : rise per metre ahead (tan of the slope angle).
    road_y : (right, left) kerb lines, y in metres (sensor frame), right < 0 < left.
    sidewalk_y : (right, left) outer edges of the sidewalks (terrain beyond), metres.
    kerb_height : height of the kerb step in metres.
    sensor_height : height of the sensor above the road in metres.
    """

    slope: float
    road_y: tuple[float, float]
    sidewalk_y: tuple[float, float]
    kerb_height: float = 0.12
    sensor_height: float = SENSOR_HEIGHT_M


#: The Moosmann recording car in its sensor frame, as the sensor sees it: a 4.5 x 1.8 m box from
#: 2.0 m ahead of the sensor to 2.5 m behind it, its top (roof, hood and trunk lumped) 0.5 m below
#: the sensor and its bottom 0.18 m above the road. Rays that hit it give no return (see
#: :func:`cast`): it hides the beams steeper than 14 deg looking ahead and 11 deg looking back
#: (10.6 deg past the rear corners); sideways even the lowest beam (25 deg) clears it.
EGO_VEHICLE: tuple[Box, ...] = (Box((-0.25, 0.0, -1.025), (2.25, 0.9, 0.525), 0.0, 0),)


@dataclass(frozen=True, eq=False)
class Scene:
    """One frame of the synthetic street, in that frame's sensor frame.

    Attributes
    ----------
    seed : the street's seed.
    frame : frame number (10 Hz).
    pose : (3, 4) float64 pose of the sensor in the world frame (the sensor frame of frame 0).
    ground : the ground surfaces.
    boxes : box primitives.
    cylinders : cylinder primitives.
    """

    seed: int
    frame: int
    pose: np.ndarray
    ground: Ground
    boxes: list[Box]
    cylinders: list[Cylinder]

    @property
    def instances(self) -> dict[int, int]:
        """Instance id -> semantic class of every thing in the scene."""
        out: dict[int, int] = {}
        for p in [*self.boxes, *self.cylinders]:
            if p.instance:
                out[p.instance] = p.semantic
        return out


@dataclass(frozen=True)
class _Mover:
    """A moving car or cyclist (world frame)."""

    x0: float  # position at frame 0, metres; a follower: phase of its distance changes, radians
    y: float  # lane centre, metres
    speed: float  # m/s along +x (negative: towards -x); unused by a follower
    follow: float | None  # a car in the ego lane keeps this distance ahead of the ego car (< 0:
    # behind), give or take 0.8 m; None = moves at ``speed`` and loops over the street
    dims: tuple[float, float, float, float]  # car: length, width, hood height, roof height;
    # cyclist: bicycle length, rider width, saddle height, head height
    instance: int
    remission: float
    cyclist: bool = False


@dataclass(frozen=True)
class _World:
    """The static street of one seed (world frame) and its moving cars and cyclists."""

    slope: float
    road_y: tuple[float, float]
    sidewalk_y: tuple[float, float]
    boxes: tuple[Box, ...]
    cylinders: tuple[Cylinder, ...]
    moving: tuple[_Mover, ...]
    wrap: tuple[float, float]  # x range over which the cyclists loop


# ---------------------------------------------------------------------------------------------
# Street generator
# ---------------------------------------------------------------------------------------------


def _car_boxes(
    x: float,
    y: float,
    zg: float,
    yaw: float,
    dims: tuple[float, float, float, float],
    semantic: int,
    instance: int,
    body_p: float,
    remission: float,
) -> list[Box]:
    """Body, roof slab and window pillars of a car standing on the ground at height ``zg``.

    Rays pass through the windows between the pillars and see what lies beyond the car, so the
    roof is separated from the body by a gap of a few rows except at the pillars.
    """
    length, width, hood, roof = dims
    c, s = float(np.cos(yaw)), float(np.sin(yaw))
    bottom = zg + 0.22
    top = zg + hood
    body = Box(
        (x, y, (bottom + top) / 2),
        (length / 2, width / 2, (top - bottom) / 2),
        yaw,
        semantic,
        instance,
        body_p,
        remission,
    )
    cab_len = 0.5 * length
    off = -0.08 * length  # the roof sits slightly behind the middle
    cx, cy = x + c * off, y + s * off
    roof_t = 0.06
    cab_half = (cab_len / 2, width / 2 - 0.06)
    slab = Box(
        (cx, cy, zg + roof - roof_t / 2),
        (*cab_half, roof_t / 2),
        yaw,
        semantic,
        instance,
        1.0,
        remission,
    )
    # Window pillars on both sides: at the windscreen, between the doors and at the rear window.
    cab_hz = (roof - roof_t - hood) / 2
    cab_z = zg + (hood + roof - roof_t) / 2
    parts = [body, slab]
    for along, half_len in (
        (cab_half[0] - 0.08, 0.08),
        (-0.04 * length, 0.06),
        (0.08 - cab_half[0], 0.08),
    ):
        for side in (-1.0, 1.0):
            across = side * (cab_half[1] - 0.05)
            px, py = cx + c * along - s * across, cy + s * along + c * across
            pillar = Box((px, py, cab_z), (half_len, 0.05, cab_hz), yaw, semantic, instance)
            parts.append(replace(pillar, remission=remission))
    return parts


class _Footprints:
    """Circles already taken on the ground plane (street coordinates), for rejection sampling."""

    def __init__(self) -> None:
        self.items: list[tuple[float, float, float]] = []

    def free(self, u: float, v: float, r: float) -> bool:
        return all((u - a) ** 2 + (v - b) ** 2 >= (r + c) ** 2 for a, b, c in self.items)

    def add(self, u: float, v: float, r: float) -> None:
        self.items.append((u, v, r))


@functools.lru_cache(maxsize=8)
def _world(seed: int) -> _World:
    """Build the static street of ``seed`` (deterministic)."""
    rng = np.random.default_rng([seed, 0x5EED])
    u01 = rng.uniform

    slope = float(np.tan(np.radians(u01(1.0, 2.0))))
    # A one-way street: one lane (v = 0 in its middle) between two parking strips.
    lane_w = float(u01(3.8, 4.2))
    kerb_v = {side: lane_w / 2 + float(u01(2.0, 2.3)) for side in (-1.0, 1.0)}  # |v| of the kerbs
    # Sidewalks: shops on the right (a cycle track along the kerb), houses with front gardens
    # (terrain) on the left.
    walk_w = {-1.0: float(u01(3.4, 4.0)), 1.0: float(u01(2.2, 2.8))}
    garden_w = {-1.0: 0.0, 1.0: float(u01(1.2, 2.0))}
    kerb = 0.12
    yc = float(u01(-0.15, 0.15))  # the lane's middle in the world frame (the ego drives at y = 0)
    u_min, u_max = -85.0, 105.0  # street ends: a building closes it at both ends
    u_lo, u_hi = -40.0, 70.0  # the stretch seen by the first 40 frames: small things go here

    def ground_z(u: float, v: float) -> float:
        """World z of the ground at street coordinates (u along, v across from the centre)."""
        on_walk = v <= -kerb_v[-1.0] or v >= kerb_v[1.0]
        return -SENSOR_HEIGHT_M + slope * u + (kerb if on_walk else 0.0)

    boxes: list[Box] = []
    cyls: list[Cylinder] = []
    taken = _Footprints()
    next_instance = [1]

    def new_instance() -> int:
        i = next_instance[0]
        next_instance[0] += 1
        return i

    def add_box(u, v, z0, size, yaw, sem, inst=0, p=1.0, facade=False, shop=False):
        length, depth, height = size
        rem = float(np.clip(_REMISSION[sem] + rng.normal(0, 0.05), 0.02, 1.0))
        half = (length / 2, depth / 2, height / 2)
        centre = (u, v + yc, z0 + height / 2)
        boxes.append(Box(centre, half, yaw, sem, inst, p, rem, facade, shopfront=shop))

    def add_cyl(u, v, r, z0, height, sem, inst=0, p=1.0):
        rem = float(np.clip(_REMISSION[sem] + rng.normal(0, 0.05), 0.02, 1.0))
        cyls.append(Cylinder((u, v + yc), r, z0, z0 + height, sem, inst, p, rem))

    def add_tree(u, v, trunk_r, trunk_h, crown_r, crown_h):
        zg = ground_z(u, v)
        add_cyl(u, v, trunk_r, zg, trunk_h, 71)
        add_cyl(u, v, crown_r, zg + trunk_h - 0.2, crown_h, 70, p=0.75)
        taken.add(u, v, trunk_r + 0.2)

    # Buildings: blocks along both sides, broken by alleys and passages (through some of which a
    # building further back is seen); a block's frontage steps back and forth by up to 2 m.
    for side in (-1.0, 1.0):
        facade_v = kerb_v[side] + walk_w[side] + garden_w[side]
        u = u_min + float(u01(0, 5))
        while u < u_max:
            height = float(u01(7.0, 18.0))
            depth = 10.0
            recessed = bool(rng.random() < 0.5)
            for _seg in range(int(rng.integers(1, 5))):
                length = float(u01(2.5, 7.0))
                recessed = not recessed  # bays, porches, recessed entrances: the frontage steps
                setback = float(u01(1.0, 2.0)) if recessed else 0.0
                v = side * (facade_v + setback + depth / 2)
                size = (length, depth, height + float(u01(-1.0, 1.0)) + 0.3)
                shop = side < 0 and rng.random() < 0.7
                zb = ground_z(u, v) - 0.3
                add_box(u + length / 2, v, zb, size, 0.0, 50, facade=True, shop=shop)
                u += length
            gap = float(u01(1.6, 4.5))
            if rng.random() < 0.4:
                vb = side * (facade_v + float(u01(8.0, 16.0)) + depth / 2)
                size = (gap + 6.0, depth, float(u01(5.0, 15.0)))
                add_box(u + gap / 2, vb, ground_z(u, vb) - 0.3, size, 0.0, 50, facade=True)
            u += gap
    # The ends of the street.
    for u0, length in ((u_max, 15.0), (u_min - 15.0, 15.0)):
        size = (length, 90.0, float(u01(14.0, 24.0)))
        add_box(u0 + length / 2, 0.0, ground_z(u0, 99.0) - 0.5, size, 0.0, 50, facade=True)

    # Front gardens: hedges, fences and low walls in segments along the back of the sidewalks;
    # shrubs and garden trees behind them.
    for side in (1.0,):
        v_walk = kerb_v[side] + walk_w[side]
        u = u_min + float(u01(0, 4))
        while u < u_max:
            length = float(u01(1.5, 5.0))
            kind = int(rng.choice(4, p=[0.5, 0.2, 0.15, 0.15]))
            if kind == 0:  # hedge
                depth = float(u01(0.6, 1.0))
                v = side * (v_walk + 0.05 + depth / 2)
                size = (length, depth, float(u01(1.2, 2.2)))
                add_box(
                    u + length / 2, v, ground_z(u, v), size, float(u01(-0.03, 0.03)), 70, p=0.85
                )
            elif kind == 1:  # fence
                v = side * (v_walk + 0.1)
                size = (length, 0.05, float(u01(1.2, 1.9)))
                add_box(u + length / 2, v, ground_z(u, v), size, 0.0, 51, p=0.85)
            elif kind == 2:  # low wall
                v = side * (v_walk + 0.15)
                size = (length, 0.25, float(u01(0.6, 1.2)))
                add_box(u + length / 2, v, ground_z(u, v), size, 0.0, 51)
            if kind != 3 and rng.random() < 0.4:
                ub = u + float(u01(0.3, 0.7)) * length
                vb = side * (v_walk + garden_w[side] - float(u01(0.4, 0.6)))
                if rng.random() < 0.4:
                    trunk = (float(u01(0.1, 0.2)), float(u01(1.6, 2.4)))
                    add_tree(ub, vb, *trunk, float(u01(1.0, 1.8)), float(u01(1.5, 3.0)))
                else:
                    size = (float(u01(0.8, 1.6)), float(u01(0.6, 1.0)), float(u01(1.8, 2.6)))
                    add_box(ub, vb, ground_z(ub, vb), size, float(u01(-0.3, 0.3)), 70, p=0.8)
            u += length + float(u01(1.2, 3.0))

    # Street trees in pits along the kerbs.
    for side in (-1.0, 1.0):
        u = u_min + float(u01(0, 6))
        while u < u_max:
            v = side * (kerb_v[side] + float(u01(0.45, 0.6)))
            if rng.random() < 0.9:
                trunk = (float(u01(0.2, 0.35)), float(u01(1.8, 2.8)))
                add_tree(u, v, *trunk, float(u01(1.2, 2.2)), float(u01(2.0, 4.0)))
            u += float(u01(4.0, 7.0))

    def furniture(kind: int, u: float, v: float) -> float:
        """Place one piece of street furniture at (u, v); its length along the street (0: none)."""
        zg = ground_z(u, v)
        if kind == 0:  # street lamp
            r = float(u01(0.1, 0.15))
            if not taken.free(u, v, r + 0.4):
                return 0.0
            add_cyl(u, v, r, zg, float(u01(5.0, 8.0)), 80)
            taken.add(u, v, r)
            return 2 * r
        if kind == 1:  # sign post with its sign
            if not taken.free(u, v, 0.45):
                return 0.0
            h = float(u01(2.2, 2.8))
            add_cyl(u, v, 0.05, zg, h, 80)
            add_box(u, v, zg + h - 0.1, (0.05, float(u01(0.5, 0.8)), 0.6), 0.0, 81)
            taken.add(u, v, 0.4)
            return 0.6
        if kind == 2:  # bollards, 1.2-1.6 m apart
            step, n = float(u01(1.2, 1.6)), int(rng.integers(2, 5))
            if not all(taken.free(u + i * step, v, 0.3) for i in range(n)):
                return 0.0
            for i in range(n):
                r, h = float(u01(0.1, 0.13)), float(u01(0.8, 1.0))
                add_cyl(u + i * step, v, r, ground_z(u + i * step, v), h, 99)
                taken.add(u + i * step, v, 0.15)
            return (n - 1) * step + 0.3
        if kind == 3:  # litter bin, post box or parking meter
            r = float(u01(0.2, 0.35))
            if not taken.free(u, v, r + 0.4):
                return 0.0
            add_cyl(u, v, r, zg, float(u01(0.9, 1.4)), 99)
            taken.add(u, v, r)
            return 2 * r
        if kind == 4:  # planter with a shrub
            if not taken.free(u, v, 0.9):
                return 0.0
            size = (float(u01(1.0, 1.6)), float(u01(0.6, 0.9)), 0.6)
            add_box(u, v, zg, size, 0.0, 99)
            shrub = (size[0] - 0.2, size[1] - 0.1, float(u01(0.5, 1.2)))
            add_box(u, v, zg + 0.6, shrub, 0.0, 70, p=0.8)
            taken.add(u, v, size[0] / 2)
            return size[0]
        if kind == 5:  # bicycles at stands along the kerb, one behind the other
            spots = [u + 0.85 + i * float(u01(2.0, 2.3)) for i in range(int(rng.integers(1, 4)))]
            if not all(taken.free(a, v, 1.0) for a in spots):
                return 0.0
            for a in spots:
                taken.add(a, v, 0.9)
                size = (1.7, 0.12, float(u01(0.9, 1.1)))
                yaw = float(u01(-0.1, 0.1))
                add_box(a, v, ground_z(a, v), size, yaw, 11, new_instance(), p=0.8)
            return spots[-1] - u + 0.85
        if kind == 6:  # utility cabinet
            if not taken.free(u, v, 0.7):
                return 0.0
            add_box(u, v, zg, (float(u01(0.7, 1.2)), 0.45, float(u01(1.1, 1.5))), 0.0, 52)
            taken.add(u, v, 0.5)
            return 1.0
        if kind == 7:  # advertising column
            r = float(u01(0.45, 0.55))
            if not taken.free(u, v, r + 0.4):
                return 0.0
            add_cyl(u, v, r, zg, float(u01(2.6, 3.4)), 52)
            taken.add(u, v, r)
            return 2 * r
        if kind == 8:  # bench
            if not taken.free(u, v, 1.1):
                return 0.0
            add_box(u, v, zg, (float(u01(1.5, 2.0)), 0.6, float(u01(0.8, 0.9))), 0.0, 99)
            taken.add(u, v, 0.9)
            return 1.8
        if kind == 9:  # cafe table with its chairs
            if not taken.free(u, v, 1.0):
                return 0.0
            add_cyl(u, v, float(u01(0.3, 0.4)), zg, 0.75, 99)
            for du in (-0.65, 0.65):
                add_box(u + du, v, zg, (0.45, 0.45, 0.9), float(u01(-0.3, 0.3)), 99)
            taken.add(u, v, 0.9)
            return 1.8
        if kind == 10:  # motorcycle or scooter parked along the kerb
            if not taken.free(u, v, 1.2):
                return 0.0
            size = (float(u01(1.7, 2.1)), float(u01(0.6, 0.8)), float(u01(1.1, 1.3)))
            add_box(u, v, zg + 0.1, size, float(u01(-0.2, 0.2)), 15, new_instance())
            taken.add(u, v, 1.0)
            return size[0]
        return 0.0

    # Street furniture between the trees, on both sidewalks (busier on the wide one beside the ego
    # lane): one row along the kerb and, on the shop side, one along the shop fronts.
    kerb_kinds = [0, 1, 2, 3, 4, 5, 6, 7, 10]
    kerb_p = [0.12, 0.12, 0.14, 0.14, 0.1, 0.16, 0.08, 0.06, 0.08]
    front_kinds = [3, 4, 5, 8, 9]
    front_p = [0.15, 0.25, 0.25, 0.15, 0.2]
    rows = [(-1.0, 0.3, 0.5, 1.2, 3.0, kerb_kinds, kerb_p)]
    rows.append((-1.0, walk_w[-1.0] - 0.6, walk_w[-1.0] - 0.4, 1.2, 3.5, front_kinds, front_p))
    rows.append((1.0, 0.4, 0.6, 2.5, 7.0, kerb_kinds, kerb_p))
    for side, v_lo, v_hi, gap_lo, gap_hi, kinds, p in rows:
        u = u_lo + float(u01(0, 3))
        while u < u_hi:
            v = side * (kerb_v[side] + float(u01(v_lo, v_hi)))
            length = furniture(int(rng.choice(kinds, p=p)), u, v)
            u += length + float(u01(gap_lo, gap_hi))

    # Parked vehicles along both kerbs, now and then a van or a truck: runs of cars, some bumper
    # to bumper, some with gaps (driveways, loading zones).
    for side in (-1.0, 1.0):
        u = u_min + float(u01(5.0, 10.0))
        while u < u_max - 12.0:
            is_truck = side > 0 and rng.random() < 0.05
            if is_truck:
                length, width = float(u01(6.5, 8.5)), float(u01(2.2, 2.45))
            else:
                length, width = float(u01(3.8, 4.8)), float(u01(1.7, 1.9))
            v = side * (kerb_v[side] - float(u01(0.15, 0.3)) - width / 2)
            uc = u + length / 2
            yaw = float(rng.choice([0.0, np.pi])) + float(u01(-0.03, 0.03))
            zg = ground_z(uc, 0.0)
            inst = new_instance()
            if is_truck:
                cab_l = 2.0
                sgn = 1.0 if abs(yaw) < 1 else -1.0
                uf = uc + sgn * (length / 2 - cab_l / 2)
                add_box(uf, v, zg + 0.4, (cab_l, width, 2.6), yaw, 18, inst)
                size = (length - cab_l - 0.2, width + 0.05, 3.2)
                add_box(uc - sgn * cab_l / 2, v, zg + 0.6, size, yaw, 18, inst)
            else:
                dark = rng.random() < 0.3
                body_p = float(u01(0.6, 0.85)) if dark else 1.0
                rem = float(u01(0.03, 0.1)) if dark else float(u01(0.3, 0.8))
                dims = (length, width, float(u01(0.85, 1.05)), float(u01(1.45, 1.65)))
                boxes.extend(_car_boxes(uc, v + yc, zg, yaw, dims, 10, inst, body_p, rem))
            r = rng.random()
            if r < 0.3:
                gap = float(u01(0.3, 0.7))  # bumper to bumper
            elif r < 0.9:
                gap = float(u01(1.0, 2.5))
            else:
                gap = float(u01(3.5, 7.0))  # a driveway or a loading zone
            u += length + gap

    # Pedestrians on the sidewalks (mostly on the shop side), some in groups.
    n_people = int(rng.integers(40, 71))
    placed = 0
    tries = 0
    while placed < n_people and tries < 1000:
        tries += 1
        side = -1.0 if rng.random() < 0.7 else 1.0
        u = float(u01(u_lo, u_hi))
        v0 = 2.2 if side < 0 else 1.0  # not on the cycle track
        v = side * (kerb_v[side] + float(u01(v0, walk_w[side] - 0.4)))
        group = min(int(rng.choice([1, 1, 1, 2, 2, 3])), n_people - placed)
        spots = [(u + i * float(u01(0.6, 1.0)), v + float(u01(-0.15, 0.15))) for i in range(group)]
        if not all(taken.free(a, b, 0.45) for a, b in spots):
            continue
        for a, b in spots:
            taken.add(a, b, 0.3)
            size = (float(u01(0.45, 0.6)), float(u01(0.35, 0.5)), float(u01(1.6, 1.9)))
            add_box(a, b, ground_z(a, b), size, float(u01(-np.pi, np.pi)), 30, new_instance())
            placed += 1

    # Traffic: a queue in the lane keeping its distance to the ego car, and cyclists both ways on
    # the cycle track.
    def car_dims() -> tuple[float, float, float, float]:
        return (
            float(u01(3.9, 4.8)),
            float(u01(1.7, 1.9)),
            float(u01(0.85, 1.05)),
            float(u01(1.45, 1.6)),
        )

    moving: list[_Mover] = []
    gaps = [float(u01(6.0, 9.0))]
    if rng.random() < 0.6:
        gaps.append(gaps[0] + float(u01(11.0, 16.0)))
    if rng.random() < 0.6:
        gaps.append(-float(u01(9.0, 14.0)))
    for gap in gaps:
        phase = float(u01(0.0, 2.0 * np.pi))
        rem = float(u01(0.2, 0.8))
        moving.append(_Mover(phase, yc, 0.0, gap, car_dims(), new_instance(), rem))
    span = u_max - u_min - 20.0
    for _ in range(int(rng.integers(2, 6))):
        x0 = u_min + 10.0 + float(u01(0.0, span))
        y = yc - kerb_v[-1.0] - 1.5
        dims = (1.75, 0.5, 1.0, float(u01(1.65, 1.85)))
        rem = float(u01(0.2, 0.6))
        speed = float(u01(4.0, 6.0)) * float(rng.choice([-1.0, 1.0]))
        moving.append(_Mover(x0, y, speed, None, dims, new_instance(), rem, cyclist=True))

    return _World(
        slope=slope,
        road_y=(yc - kerb_v[-1.0], yc + kerb_v[1.0]),
        sidewalk_y=(yc - kerb_v[-1.0] - walk_w[-1.0], yc + kerb_v[1.0] + walk_w[1.0]),
        boxes=tuple(boxes),
        cylinders=tuple(cyls),
        moving=tuple(moving),
        wrap=(u_min + 10.0, u_max - 10.0),
    )


def _ego_x(frame: int) -> float:
    """Ego position along the street at ``frame`` in metres (1 m/frame, then stops at ~60 m).

    The street is finite: after 40 frames the ego car brakes smoothly and waits ~35 m before the
    building at the end of the street (moving cars keep moving, so frames still differ).
    """
    step = _EGO_SPEED / _FPS
    k = float(frame)
    if k <= 40.0:
        return step * k
    return step * (40.0 + 20.0 * (1.0 - np.exp(-(k - 40.0) / 20.0)))


def make_scene(seed: int, frame: int) -> Scene:
    """The street of ``seed`` as seen from the sensor at ``frame``.

    Parameters
    ----------
    seed : street seed; it fixes every object of the street.
    frame : frame number (10 Hz). The ego car moves forward 1 m per frame (and stops after about
        60 m); the cars in its lane keep their distance to it, cyclists ride at 4-6 m/s.

    Returns
    -------
    Scene
        Primitives in the sensor frame of this frame (metres) and the sensor pose in the world frame
        (the sensor frame of frame 0).
    """
    w = _world(int(seed))
    ex = _ego_x(frame)
    ez = w.slope * ex  # the sensor rides the slope at a constant height above the road
    pose = np.array([[1.0, 0, 0, ex], [0, 1.0, 0, 0], [0, 0, 1.0, ez]], dtype=np.float64)

    def shift_box(b: Box) -> Box:
        x, y, z = b.center
        return Box(
            (x - ex, y, z - ez),
            b.half,
            b.yaw,
            b.semantic,
            b.instance,
            b.p_return,
            b.remission,
            b.facade,
            b.shopfront,
        )

    boxes = [shift_box(b) for b in w.boxes]
    cyls = [
        Cylinder(
            (c.center[0] - ex, c.center[1]),
            c.radius,
            c.z_min - ez,
            c.z_max - ez,
            c.semantic,
            c.instance,
            c.p_return,
            c.remission,
        )
        for c in w.cylinders
    ]
    t = frame / _FPS
    lo, hi = w.wrap
    for m in w.moving:
        if m.follow is not None:
            x = ex + m.follow + 0.8 * float(np.sin(0.6 * t + m.x0))
        else:
            x = lo + (m.x0 + m.speed * t - lo) % (hi - lo)
        zg = -SENSOR_HEIGHT_M + w.slope * x
        if m.cyclist:
            length, width, saddle, top = m.dims
            bike = Box((x, m.y, zg + saddle / 2), (length / 2, 0.08, saddle / 2), 0.0, 31)
            rider = Box(
                (x - 0.1, m.y, (zg + saddle + zg + top) / 2),
                (0.25, width / 2, (top - saddle) / 2),
                0.0,
                31,
            )
            for b in (bike, rider):
                boxes.append(
                    shift_box(replace(b, instance=m.instance, p_return=0.8, remission=m.remission))
                )
            continue
        yaw = np.pi if m.speed < 0 else 0.0
        for b in _car_boxes(x, m.y, zg, yaw, m.dims, 252, m.instance, 1.0, m.remission):
            boxes.append(shift_box(b))
    ground = Ground(w.slope, w.road_y, w.sidewalk_y)
    return Scene(int(seed), int(frame), pose, ground, boxes, cyls)


# ---------------------------------------------------------------------------------------------
# Ray casting
# ---------------------------------------------------------------------------------------------


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


def _cast_full(
    scene: Scene,
    pitch_deg: np.ndarray,
    azimuths_rad: np.ndarray,
    rng: np.random.Generator,
    vehicle: tuple[Box, ...] = (),
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`cast` plus the remission of every return."""
    pitch = np.asarray(pitch_deg, dtype=np.float64).reshape(-1)
    az = np.asarray(azimuths_rad, dtype=np.float64).reshape(-1)
    h, w = pitch.size, az.size
    elev = -np.radians(pitch)
    ce, se = np.cos(elev), np.sin(elev)
    dx = ce[:, None] * np.cos(az)[None, :]
    dy = ce[:, None] * np.sin(az)[None, :]
    dz = np.broadcast_to(se[:, None], (h, w))

    g = scene.ground
    # --- ground: road plane, raised sidewalk/terrain plane and the two kerb faces -------------
    best_t = np.full((h, w), np.inf)
    sem = np.zeros((h, w), dtype=np.uint16)
    inst = np.zeros((h, w), dtype=np.uint16)
    p_ret = np.ones((h, w))
    rem = np.zeros((h, w))
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
                sem[better] = 40
            else:
                yo = y[better]
                sw = (yo > g.sidewalk_y[0]) & (yo < g.sidewalk_y[1])
                sem[better] = np.where(sw, 48, 72)
        for y_k in (y_r, y_l):
            t = y_k / _safe(dy)
            z = t * dz
            zr = -g.sensor_height + g.slope * t * dx
            ok = (t > 0) & (z >= zr) & (z <= zr + g.kerb_height)
            better = ok & (t < best_t)
            best_t[better] = t[better]
            sem[better] = 48
    ground_hit = np.isfinite(best_t)
    rem[ground_hit] = np.vectorize(_REMISSION.get, otypes=[float])(sem[ground_hit])
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
    u = rng.random((h, w))
    noise = rng.normal(0.0, 0.015, (h, w))
    global_drop = 0.015
    # Dark paint returns less and less with range (full up to 2 m, the base rate from 15 m on).
    dark = (rem < 0.12) & (p_ret < 1.0)
    p_ret = np.where(dark, 1.0 - (1.0 - p_ret) * np.clip((best_t - 2.0) / 13.0, 0.0, 1.0), p_ret)
    valid = np.isfinite(best_t) & (best_t <= MAX_RANGE_M)
    if vehicle:
        valid &= ~_vehicle_hits(vehicle, dx, dy, dz)
    valid &= u < p_ret * (1.0 - global_drop)
    ranges = np.where(valid, best_t + noise, 0.0)
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
    rng: np.random.Generator,
    vehicle: tuple[Box, ...] = (),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cast a grid of rays from the sensor into the scene (first hit, vectorised over rays).

    Parameters
    ----------
    scene : the frame's scene (:func:`make_scene`).
    pitch_deg : (H,) beam pitch in degrees, positive = downward, one per image row.
    azimuths_rad : (W,) column azimuth in radians (counter-clockwise from +x), one per column.
    rng : source of the sensor noise (range noise, dropouts); pass a seeded generator for
        reproducible output.
    vehicle : boxes of the recording car in the sensor frame (axis-aligned, e.g.
        :data:`EGO_VEHICLE`); a ray that hits one returns nothing. Default: none.

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
    ranges, sem, inst, _ = _cast_full(scene, pitch_deg, azimuths_rad, rng, vehicle)
    return ranges, sem, inst


def moosmann_azimuths(width: int = MOOSMANN_WIDTH) -> np.ndarray:
    """(W,) azimuth of each column of a Moosmann image in radians: +180 - 360 * c / (W - 1) deg."""
    return np.radians(180.0 - 360.0 * np.arange(width) / (width - 1))


def kitti_azimuths(width: int = 2048) -> np.ndarray:
    """(W,) azimuths of one KITTI ring in scan order: ``2 pi (k + 0.5) / W``, radians."""
    return 2.0 * np.pi * (np.arange(width) + 0.5) / width


# ---------------------------------------------------------------------------------------------
# Writing the sample
# ---------------------------------------------------------------------------------------------


@dataclass
class SamplePaths:
    """Where a written sample lies.

    Attributes
    ----------
    kitti_root : the SemanticKITTI root (``<out>/semantickitti``, holding ``sequences/00``).
    moosmann_log : the Moosmann-style log folder (``<out>/moosmann``).
    seed, frames, kitti_width : the parameters it was written with.
    """

    kitti_root: Path
    moosmann_log: Path
    seed: int = 0
    frames: int = 20
    kitti_width: int = 2048
    _truth: dict[int, tuple[np.ndarray, np.ndarray]] = field(
        default_factory=dict, repr=False, compare=False
    )

    @property
    def kitti_sequence(self) -> Path:
        """The sequence folder ``<kitti_root>/sequences/00``."""
        return self.kitti_root / "sequences" / "00"

    def moosmann_truth(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """Ground truth of a Moosmann frame, which the format itself cannot hold.

        Returns
        -------
        semantic, instance : (64, 870) uint16 arrays, per pixel (0 where there is no return).
        """
        if frame not in self._truth:
            _, sem, inst = _moosmann_frame(self.seed, frame)
            self._truth[frame] = (sem, inst)
        return self._truth[frame]


def _atomic_write(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same folder."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


def _moosmann_frame(seed: int, frame: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ranges, semantic, instance) of a Moosmann frame, 64 x 870."""
    rng = np.random.default_rng([seed, frame, 2])
    scene = make_scene(seed, frame)
    return cast(scene, HDL64_PITCH_DEG, moosmann_azimuths(), rng, EGO_VEHICLE)


def _kitti_frame(seed: int, frame: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Points (N, 4) float32 in scan order and labels (N,) uint32 of a KITTI frame."""
    rng = np.random.default_rng([seed, frame, 1])
    az = kitti_azimuths(width)
    scene = make_scene(seed, frame)
    ranges, sem, inst, rem = _cast_full(scene, HDL64_PITCH_DEG, az, rng)
    el = -np.radians(HDL64_PITCH_DEG)[:, None]
    r = ranges.astype(np.float64)
    xyz = np.stack(
        [
            r * np.cos(el) * np.cos(az),
            r * np.cos(el) * np.sin(az),
            r * np.sin(el) * np.ones_like(az),
        ],
        axis=-1,
    )
    keep = (ranges > 0).reshape(-1)  # row-major = ring after ring, each ring counter-clockwise
    pts = np.concatenate([xyz.reshape(-1, 3), rem.reshape(-1, 1)], axis=1)[keep]
    labels = sem.reshape(-1).astype(np.uint32) | (inst.reshape(-1).astype(np.uint32) << 16)
    return pts.astype("<f4"), labels[keep].astype("<u4")


_CALIB = (
    "P0: 7.188560e+02 0.000000e+00 6.071928e+02 0.000000e+00 0.000000e+00 7.188560e+02 "
    "1.852157e+02 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00\n"
    "P1: 7.188560e+02 0.000000e+00 6.071928e+02 -3.861448e+02 0.000000e+00 7.188560e+02 "
    "1.852157e+02 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00\n"
    "P2: 7.188560e+02 0.000000e+00 6.071928e+02 4.538225e+01 0.000000e+00 7.188560e+02 "
    "1.852157e+02 -1.130887e-01 0.000000e+00 0.000000e+00 1.000000e+00 3.779761e-03\n"
    "P3: 7.188560e+02 0.000000e+00 6.071928e+02 -3.372877e+02 0.000000e+00 7.188560e+02 "
    "1.852157e+02 2.369057e+00 0.000000e+00 0.000000e+00 1.000000e+00 4.915215e-03\n"
    "Tr: 1.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 "
    "0.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00\n"
)


def _png_bytes(image: np.ndarray) -> bytes:
    """A 16-bit greyscale PNG of a uint16 image."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image, dtype=np.uint16)).save(buf, format="PNG")
    return buf.getvalue()


def write_sample(
    out: Path, frames: int = 20, seed: int = 0, kitti_width: int = 2048
) -> SamplePaths:
    """Write the synthetic street as a SemanticKITTI sequence and as a Moosmann-style log.

    Layout::

        out/semantickitti/sequences/00/velodyne/000000.bin   float32 x, y, z, remission
        out/semantickitti/sequences/00/labels/000000.label   uint32 semantic | instance << 16
        out/semantickitti/sequences/00/{calib,poses,times}.txt
        out/moosmann/img.cfg
        out/moosmann/scan00000.png                            16-bit, range_m * 500, 0 = none

    Parameters
    ----------
    out : output folder (created).
    frames : number of frames (10 Hz).
    seed : street seed.
    kitti_width : rays per ring of the KITTI scans (azimuth resolution 360 deg / width).

    Returns
    -------
    SamplePaths
        The two dataset roots; the Moosmann ground truth of the written frames is kept in memory
        (:meth:`SamplePaths.moosmann_truth`), since the format has no labels.
    """
    out = Path(out)
    seq = out / "semantickitti" / "sequences" / "00"
    velo, lab = seq / "velodyne", seq / "labels"
    moos = out / "moosmann"
    for d in (velo, lab, moos):
        d.mkdir(parents=True, exist_ok=True)
    paths = SamplePaths(out / "semantickitti", moos, seed, frames, kitti_width)

    poses, times = [], []
    for k in range(frames):
        pts, labels = _kitti_frame(seed, k, kitti_width)
        _atomic_write(velo / f"{k:06d}.bin", pts.tobytes())
        _atomic_write(lab / f"{k:06d}.label", labels.tobytes())
        ranges, sem, inst = _moosmann_frame(seed, k)
        img = np.round(ranges.astype(np.float64) * 500.0).astype(np.uint16)
        _atomic_write(moos / f"scan{k:05d}.png", _png_bytes(img))
        paths._truth[k] = (sem, inst)
        pose = make_scene(seed, k).pose
        poses.append(" ".join(f"{v:.6e}" for v in pose.reshape(-1)))
        times.append(f"{k / _FPS:.6e}")

    _atomic_write(seq / "calib.txt", _CALIB.encode())
    _atomic_write(seq / "poses.txt", ("\n".join(poses) + "\n").encode())
    _atomic_write(seq / "times.txt", ("\n".join(times) + "\n").encode())
    cfg = (
        "# synthetic HDL-64E street (flic sample): imgHSize; imgVSize; horizStartAngle; "
        "horizStopAngle; vertAngle_1..64 (deg, positive = down)\n"
        f"{MOOSMANN_WIDTH}; {MOOSMANN_HEIGHT}; 180; -180; "
        + "; ".join(f"{a:.4f}" for a in HDL64_PITCH_DEG)
        + ";\n"
    )
    _atomic_write(moos / "img.cfg", cfg.encode())
    return paths


def default_sample_dir() -> Path:
    """Per-user cache folder of the embedded sample: ``$FLIC_SAMPLE_DIR`` or
    ``~/.cache/flic/sample-v2`` (the version changes whenever the generated content does)."""
    env = os.environ.get("FLIC_SAMPLE_DIR")
    if env:
        return Path(env).expanduser()
    return Path.home() / ".cache" / "flic" / "sample-v2"


def ensure_sample(frames: int = 20, seed: int = 0) -> SamplePaths:
    """The default sample in :func:`default_sample_dir`, written on first use.

    The sample is written into a temporary folder beside the target and renamed into place, with
    a ``.complete`` marker recording its parameters; a killed run leaves no half-written sample.
    A folder written with other parameters is replaced.

    Parameters
    ----------
    frames : number of frames.
    seed : street seed.

    Returns
    -------
    SamplePaths
    """
    target = default_sample_dir()
    stamp = f"seed={seed} frames={frames} kitti_width=2048\n"
    marker = target / ".complete"

    def paths() -> SamplePaths:
        return SamplePaths(target / "semantickitti", target / "moosmann", seed, frames, 2048)

    if marker.is_file() and marker.read_text() == stamp:
        return paths()
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}-", dir=target.parent))
    try:
        written = write_sample(tmp, frames=frames, seed=seed)
        (tmp / ".complete").write_text(stamp)
        if target.exists():
            if marker.is_file() and marker.read_text() == stamp:  # written meanwhile
                shutil.rmtree(tmp, ignore_errors=True)
                return paths()
            shutil.rmtree(target)
        try:
            os.replace(tmp, target)
        except OSError:
            # Another process renamed its copy into place first.
            if not (marker.is_file() and marker.read_text() == stamp):
                raise
            shutil.rmtree(tmp, ignore_errors=True)
            return paths()
        result = paths()
        result._truth.update(written._truth)
        return result
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
