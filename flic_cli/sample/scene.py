"""Scene primitives: boxes, vertical cylinders, the ground (road, kerbs, sidewalks, terrain).

Every primitive lives in the sensor frame (x forward, y left, z up, metres; the sensor at the
origin, level, looking along +x) and carries a SemanticKITTI raw class id and, for things, an
instance id (0 for stuff). :class:`Scene` bundles them with a :class:`Ground`; :func:`custom_scene`
builds one from any primitives, and :func:`person` and :func:`car` stand a person or a car on the
ground, so that a test can describe a targeted scene in a few lines.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

import numpy as np

from flic_cli.classes import CLASS_NAMES

__all__ = [
    "SENSOR_HEIGHT_M",
    "Box",
    "Cylinder",
    "Ground",
    "Scene",
    "car",
    "custom_scene",
    "person",
]

#: Height of the sensor above the road in metres.
SENSOR_HEIGHT_M: float = 1.73

_ID = {name: cid for cid, name in CLASS_NAMES.items()}
# The SemanticKITTI raw class ids that the sample uses (from flic_cli.classes, by name).
CAR, BICYCLE, MOTORCYCLE, TRUCK = _ID["car"], _ID["bicycle"], _ID["motorcycle"], _ID["truck"]
PERSON, BICYCLIST, MOVING_CAR = _ID["person"], _ID["bicyclist"], _ID["moving-car"]
ROAD, SIDEWALK, TERRAIN = _ID["road"], _ID["sidewalk"], _ID["terrain"]
BUILDING, FENCE, OTHER_STRUCTURE = _ID["building"], _ID["fence"], _ID["other-structure"]
VEGETATION, TRUNK, POLE = _ID["vegetation"], _ID["trunk"], _ID["pole"]
TRAFFIC_SIGN, OTHER_OBJECT = _ID["traffic-sign"], _ID["other-object"]

#: Base remission (0..1) per SemanticKITTI class.
REMISSION: dict[int, float] = {
    ROAD: 0.22,
    SIDEWALK: 0.30,
    TERRAIN: 0.38,
    BUILDING: 0.28,
    FENCE: 0.20,
    VEGETATION: 0.45,
    TRUNK: 0.30,
    POLE: 0.55,
    CAR: 0.40,
    MOVING_CAR: 0.40,
    PERSON: 0.35,
    BICYCLE: 0.30,
    MOTORCYCLE: 0.35,
    BICYCLIST: 0.30,
    TRUCK: 0.50,
    OTHER_STRUCTURE: 0.35,
    TRAFFIC_SIGN: 0.70,
    OTHER_OBJECT: 0.45,
}


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
    terrain lie ``kerb_height`` higher. The kerb lines run along x (the sensor looks along the
    street); a vertical kerb face joins the two levels at each kerb line.

    Attributes
    ----------
    slope : rise per metre ahead (tan of the slope angle).
    road_y : (right, left) kerb lines, y in metres (sensor frame), right < left.
    sidewalk_y : (right, left) outer edges of the sidewalks (terrain beyond), metres.
    kerb_height : height of the kerb step in metres.
    sensor_height : height of the sensor above the road in metres.
    """

    slope: float
    road_y: tuple[float, float]
    sidewalk_y: tuple[float, float]
    kerb_height: float = 0.12
    sensor_height: float = SENSOR_HEIGHT_M

    @classmethod
    def flat(cls, sensor_height: float = SENSOR_HEIGHT_M, slope: float = 0.0) -> Ground:
        """Road everywhere: no kerb, no sidewalk (a plane ``z = -sensor_height + slope * x``)."""
        return cls(slope, (-np.inf, np.inf), (-np.inf, np.inf), 0.0, sensor_height)

    def height(self, x: float, y: float) -> float:
        """z of the ground surface at (x, y) in metres (sensor frame): road, or kerb-high beside it.

        A point exactly on a kerb line counts as sidewalk.
        """
        on_road = self.road_y[0] < y < self.road_y[1]
        return -self.sensor_height + self.slope * x + (0.0 if on_road else self.kerb_height)


@dataclass(frozen=True, eq=False)
class Scene:
    """One frame of a scene, in that frame's sensor frame.

    Attributes
    ----------
    seed : the street's seed (:func:`custom_scene`: 0).
    frame : frame number (10 Hz; :func:`custom_scene`: 0).
    pose : (3, 4) float64 pose of the sensor in the world frame (the sensor frame of frame 0).
    ground : the ground surfaces; None = no ground (rays that miss every primitive return
        nothing).
    boxes : box primitives.
    cylinders : cylinder primitives.
    """

    seed: int
    frame: int
    pose: np.ndarray
    ground: Ground | None
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

    def seen_from(self, x: float, y: float = 0.0) -> Scene:
        """The same scene seen by the sensor moved to ``(x, y)`` of this frame (no rotation).

        The sensor rides the road's slope at its height above the road (as the ego car does), so
        everything moves by ``(-x, -y, -slope * x)``; the kerb lines move by ``-y``.

        Parameters
        ----------
        x, y : where the sensor goes, metres, in this scene's sensor frame.

        Returns
        -------
        Scene
            With the pose updated (``pose @ [x, y, slope x, 1]``).
        """
        g = self.ground
        dz = 0.0 if g is None else g.slope * x
        boxes = [
            replace(b, center=(b.center[0] - x, b.center[1] - y, b.center[2] - dz))
            for b in self.boxes
        ]
        cyls = [
            replace(
                c, center=(c.center[0] - x, c.center[1] - y), z_min=c.z_min - dz, z_max=c.z_max - dz
            )
            for c in self.cylinders
        ]
        if g is not None:
            g = replace(
                g,
                road_y=(g.road_y[0] - y, g.road_y[1] - y),
                sidewalk_y=(g.sidewalk_y[0] - y, g.sidewalk_y[1] - y),
            )
        pose = np.array(self.pose, dtype=np.float64, copy=True)
        pose[:, 3] = pose @ np.array([x, y, dz, 1.0])
        return Scene(self.seed, self.frame, pose, g, boxes, cyls)


def custom_scene(
    *primitives: Box | Cylinder | Iterable[Box | Cylinder],
    ground: Ground | None = None,
) -> Scene:
    """A scene of the given primitives (sensor frame) over ``ground``.

    Parameters
    ----------
    *primitives : boxes and cylinders, or iterables of them (e.g. what :func:`car` returns).
    ground : the ground; None (default) = :meth:`Ground.flat` (road everywhere,
        :data:`SENSOR_HEIGHT_M` below the sensor). Pass ``Ground(...)`` for kerbs, sidewalks and a
        slope; for no ground at all, build ``Scene(0, 0, pose, None, boxes, cylinders)``.

    Returns
    -------
    Scene
        Seed 0, frame 0, identity pose.
    """
    boxes: list[Box] = []
    cyls: list[Cylinder] = []
    stack = list(primitives)
    while stack:
        p = stack.pop(0)
        if isinstance(p, Box):
            boxes.append(p)
        elif isinstance(p, Cylinder):
            cyls.append(p)
        elif isinstance(p, Iterable):
            stack[:0] = list(p)
        else:
            raise TypeError(f"expected a Box, a Cylinder or an iterable of them, got {p!r}")
    pose = np.eye(3, 4, dtype=np.float64)
    return Scene(0, 0, pose, Ground.flat() if ground is None else ground, boxes, cyls)


def person(
    x: float,
    y: float,
    instance: int,
    *,
    ground: Ground | None = None,
    size: tuple[float, float, float] = (0.5, 0.4, 1.75),
    yaw: float = 0.0,
    semantic: int = PERSON,
) -> Box:
    """A person (a box) standing on the ground at ``(x, y)``.

    Parameters
    ----------
    x, y : centre of the footprint, metres, sensor frame.
    instance : instance id (> 0 for a thing).
    ground : where the feet stand (:meth:`Ground.height`); None = the flat road
        (``z = -SENSOR_HEIGHT_M``).
    size : (length along x, width along y, height) in metres before the yaw.
    yaw : rotation about z in radians.
    semantic : class id (default: person).
    """
    zg = (ground or Ground.flat()).height(x, y)
    length, width, height = size
    return Box(
        (x, y, zg + height / 2),
        (length / 2, width / 2, height / 2),
        yaw,
        semantic,
        instance,
        remission=REMISSION.get(semantic, 0.3),
    )


def car(
    x: float,
    y: float,
    instance: int,
    *,
    ground: Ground | None = None,
    dims: tuple[float, float, float, float] = (4.4, 1.8, 0.95, 1.55),
    yaw: float = 0.0,
    semantic: int = CAR,
    remission: float = 0.4,
    body_p: float = 1.0,
) -> list[Box]:
    """A car standing on the ground at ``(x, y)``: body, roof slab and window pillars.

    Rays pass through the windows between the pillars and see what lies beyond the car, as in the
    generated street.

    Parameters
    ----------
    x, y : centre of the footprint, metres, sensor frame.
    instance : instance id.
    ground : where it stands (:meth:`Ground.height` under its centre); None = the flat road.
    dims : length, width, hood height, roof height in metres.
    yaw : heading about z in radians (0 = along +x).
    semantic : class id (default: car; the street's moving cars use moving-car).
    remission : reflectivity of every part (0..1).
    body_p : return probability of the body (below 1: dark paint, see :func:`cast`).
    """
    zg = (ground or Ground.flat()).height(x, y)
    return car_parts(x, y, zg, yaw, dims, semantic, instance, body_p, remission)


def car_parts(
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
