"""The synthetic street: a deterministic one-way street per seed, seen from a moving ego car.

One straight one-way street per seed, in a world frame equal to the sensor frame of frame 0 (x
forward along the street, y left, z up, metres). The ego car drives down its single 3.8-4.2 m lane
at 10 m/s (1 m per frame at 10 Hz) and its sensor sits :data:`SENSOR_HEIGHT_M` above the road. See
the package docstring (:mod:`flic_cli.sample`) for what lines the street. :func:`make_scene` gives
the street of a seed as seen from the sensor at one frame.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np

from flic_cli.sample.scene import (
    BICYCLE,
    BICYCLIST,
    BUILDING,
    CAR,
    FENCE,
    MOTORCYCLE,
    MOVING_CAR,
    OTHER_OBJECT,
    OTHER_STRUCTURE,
    PERSON,
    POLE,
    REMISSION,
    SENSOR_HEIGHT_M,
    TRAFFIC_SIGN,
    TRUCK,
    TRUNK,
    VEGETATION,
    Box,
    Cylinder,
    Ground,
    Scene,
    car_parts,
)

__all__ = ["FPS", "make_scene"]

#: Frame rate of the sensor (Hz) and speed of the ego car (m/s).
FPS: float = 10.0
_EGO_SPEED = 10.0


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
        rem = float(np.clip(REMISSION[sem] + rng.normal(0, 0.05), 0.02, 1.0))
        half = (length / 2, depth / 2, height / 2)
        centre = (u, v + yc, z0 + height / 2)
        boxes.append(Box(centre, half, yaw, sem, inst, p, rem, facade, shopfront=shop))

    def add_cyl(u, v, r, z0, height, sem, inst=0, p=1.0):
        rem = float(np.clip(REMISSION[sem] + rng.normal(0, 0.05), 0.02, 1.0))
        cyls.append(Cylinder((u, v + yc), r, z0, z0 + height, sem, inst, p, rem))

    def add_tree(u, v, trunk_r, trunk_h, crown_r, crown_h):
        zg = ground_z(u, v)
        add_cyl(u, v, trunk_r, zg, trunk_h, TRUNK)
        add_cyl(u, v, crown_r, zg + trunk_h - 0.2, crown_h, VEGETATION, p=0.75)
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
                add_box(u + length / 2, v, zb, size, 0.0, BUILDING, facade=True, shop=shop)
                u += length
            gap = float(u01(1.6, 4.5))
            if rng.random() < 0.4:
                vb = side * (facade_v + float(u01(8.0, 16.0)) + depth / 2)
                size = (gap + 6.0, depth, float(u01(5.0, 15.0)))
                add_box(u + gap / 2, vb, ground_z(u, vb) - 0.3, size, 0.0, BUILDING, facade=True)
            u += gap
    # The ends of the street.
    for u0, length in ((u_max, 15.0), (u_min - 15.0, 15.0)):
        size = (length, 90.0, float(u01(14.0, 24.0)))
        add_box(u0 + length / 2, 0.0, ground_z(u0, 99.0) - 0.5, size, 0.0, BUILDING, facade=True)

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
                    u + length / 2,
                    v,
                    ground_z(u, v),
                    size,
                    float(u01(-0.03, 0.03)),
                    VEGETATION,
                    p=0.85,
                )
            elif kind == 1:  # fence
                v = side * (v_walk + 0.1)
                size = (length, 0.05, float(u01(1.2, 1.9)))
                add_box(u + length / 2, v, ground_z(u, v), size, 0.0, FENCE, p=0.85)
            elif kind == 2:  # low wall
                v = side * (v_walk + 0.15)
                size = (length, 0.25, float(u01(0.6, 1.2)))
                add_box(u + length / 2, v, ground_z(u, v), size, 0.0, FENCE)
            if kind != 3 and rng.random() < 0.4:
                ub = u + float(u01(0.3, 0.7)) * length
                vb = side * (v_walk + garden_w[side] - float(u01(0.4, 0.6)))
                if rng.random() < 0.4:
                    trunk = (float(u01(0.1, 0.2)), float(u01(1.6, 2.4)))
                    add_tree(ub, vb, *trunk, float(u01(1.0, 1.8)), float(u01(1.5, 3.0)))
                else:
                    size = (float(u01(0.8, 1.6)), float(u01(0.6, 1.0)), float(u01(1.8, 2.6)))
                    add_box(
                        ub, vb, ground_z(ub, vb), size, float(u01(-0.3, 0.3)), VEGETATION, p=0.8
                    )
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
            add_cyl(u, v, r, zg, float(u01(5.0, 8.0)), POLE)
            taken.add(u, v, r)
            return 2 * r
        if kind == 1:  # sign post with its sign
            if not taken.free(u, v, 0.45):
                return 0.0
            h = float(u01(2.2, 2.8))
            add_cyl(u, v, 0.05, zg, h, POLE)
            add_box(u, v, zg + h - 0.1, (0.05, float(u01(0.5, 0.8)), 0.6), 0.0, TRAFFIC_SIGN)
            taken.add(u, v, 0.4)
            return 0.6
        if kind == 2:  # bollards, 1.2-1.6 m apart
            step, n = float(u01(1.2, 1.6)), int(rng.integers(2, 5))
            if not all(taken.free(u + i * step, v, 0.3) for i in range(n)):
                return 0.0
            for i in range(n):
                r, h = float(u01(0.1, 0.13)), float(u01(0.8, 1.0))
                add_cyl(u + i * step, v, r, ground_z(u + i * step, v), h, OTHER_OBJECT)
                taken.add(u + i * step, v, 0.15)
            return (n - 1) * step + 0.3
        if kind == 3:  # litter bin, post box or parking meter
            r = float(u01(0.2, 0.35))
            if not taken.free(u, v, r + 0.4):
                return 0.0
            add_cyl(u, v, r, zg, float(u01(0.9, 1.4)), OTHER_OBJECT)
            taken.add(u, v, r)
            return 2 * r
        if kind == 4:  # planter with a shrub
            if not taken.free(u, v, 0.9):
                return 0.0
            size = (float(u01(1.0, 1.6)), float(u01(0.6, 0.9)), 0.6)
            add_box(u, v, zg, size, 0.0, OTHER_OBJECT)
            shrub = (size[0] - 0.2, size[1] - 0.1, float(u01(0.5, 1.2)))
            add_box(u, v, zg + 0.6, shrub, 0.0, VEGETATION, p=0.8)
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
                add_box(a, v, ground_z(a, v), size, yaw, BICYCLE, new_instance(), p=0.8)
            return spots[-1] - u + 0.85
        if kind == 6:  # utility cabinet
            if not taken.free(u, v, 0.7):
                return 0.0
            add_box(
                u, v, zg, (float(u01(0.7, 1.2)), 0.45, float(u01(1.1, 1.5))), 0.0, OTHER_STRUCTURE
            )
            taken.add(u, v, 0.5)
            return 1.0
        if kind == 7:  # advertising column
            r = float(u01(0.45, 0.55))
            if not taken.free(u, v, r + 0.4):
                return 0.0
            add_cyl(u, v, r, zg, float(u01(2.6, 3.4)), OTHER_STRUCTURE)
            taken.add(u, v, r)
            return 2 * r
        if kind == 8:  # bench
            if not taken.free(u, v, 1.1):
                return 0.0
            add_box(u, v, zg, (float(u01(1.5, 2.0)), 0.6, float(u01(0.8, 0.9))), 0.0, OTHER_OBJECT)
            taken.add(u, v, 0.9)
            return 1.8
        if kind == 9:  # cafe table with its chairs
            if not taken.free(u, v, 1.0):
                return 0.0
            add_cyl(u, v, float(u01(0.3, 0.4)), zg, 0.75, OTHER_OBJECT)
            for du in (-0.65, 0.65):
                add_box(u + du, v, zg, (0.45, 0.45, 0.9), float(u01(-0.3, 0.3)), OTHER_OBJECT)
            taken.add(u, v, 0.9)
            return 1.8
        if kind == 10:  # motorcycle or scooter parked along the kerb
            if not taken.free(u, v, 1.2):
                return 0.0
            size = (float(u01(1.7, 2.1)), float(u01(0.6, 0.8)), float(u01(1.1, 1.3)))
            add_box(u, v, zg + 0.1, size, float(u01(-0.2, 0.2)), MOTORCYCLE, new_instance())
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
                add_box(uf, v, zg + 0.4, (cab_l, width, 2.6), yaw, TRUCK, inst)
                size = (length - cab_l - 0.2, width + 0.05, 3.2)
                add_box(uc - sgn * cab_l / 2, v, zg + 0.6, size, yaw, TRUCK, inst)
            else:
                dark = rng.random() < 0.3
                body_p = float(u01(0.6, 0.85)) if dark else 1.0
                rem = float(u01(0.03, 0.1)) if dark else float(u01(0.3, 0.8))
                dims = (length, width, float(u01(0.85, 1.05)), float(u01(1.45, 1.65)))
                boxes.extend(car_parts(uc, v + yc, zg, yaw, dims, CAR, inst, body_p, rem))
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
            add_box(a, b, ground_z(a, b), size, float(u01(-np.pi, np.pi)), PERSON, new_instance())
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
    step = _EGO_SPEED / FPS
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
    t = frame / FPS
    lo, hi = w.wrap
    for m in w.moving:
        if m.follow is not None:
            x = ex + m.follow + 0.8 * float(np.sin(0.6 * t + m.x0))
        else:
            x = lo + (m.x0 + m.speed * t - lo) % (hi - lo)
        zg = -SENSOR_HEIGHT_M + w.slope * x
        if m.cyclist:
            length, width, saddle, top = m.dims
            bike = Box((x, m.y, zg + saddle / 2), (length / 2, 0.08, saddle / 2), 0.0, BICYCLIST)
            rider = Box(
                (x - 0.1, m.y, (zg + saddle + zg + top) / 2),
                (0.25, width / 2, (top - saddle) / 2),
                0.0,
                BICYCLIST,
            )
            for b in (bike, rider):
                boxes.append(
                    shift_box(replace(b, instance=m.instance, p_return=0.8, remission=m.remission))
                )
            continue
        yaw = np.pi if m.speed < 0 else 0.0
        for b in car_parts(x, m.y, zg, yaw, m.dims, MOVING_CAR, m.instance, 1.0, m.remission):
            boxes.append(shift_box(b))
    ground = Ground(w.slope, w.road_y, w.sidewalk_y)
    return Scene(int(seed), int(frame), pose, ground, boxes, cyls)
