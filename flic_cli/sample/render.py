"""Render a scene as the datasets store it: a SemanticKITTI scan, a Moosmann range image.

These are the entry points for tests that need a targeted scene (two people 1 m apart, a kerb, a
slope, a car 20 m away): build it with :func:`~flic_cli.sample.custom_scene` and render it with
:func:`render_kitti` or :func:`render_moosmann`. The sample writer renders the synthetic street
with the same functions (with sensor noise on).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from flic_cli.io.moosmann import RANGE_SCALE
from flic_cli.labels import encode
from flic_cli.range_image import RangeImage, from_sensor_image
from flic_cli.sample.scene import Box, Scene
from flic_cli.sample.sensor import (
    HDL64_PITCH_DEG,
    MOOSMANN_WIDTH,
    cast,
    cast_full,
    kitti_azimuths,
    moosmann_azimuths,
)

__all__ = ["MoosmannRender", "render_kitti", "render_moosmann"]


def render_kitti(
    scene: Scene,
    *,
    width: int = 2048,
    pitch_deg: np.ndarray = HDL64_PITCH_DEG,
    noise: bool = False,
    rng: np.random.Generator | None = None,
    vehicle: tuple[Box, ...] = (),
) -> tuple[np.ndarray, np.ndarray]:
    """A SemanticKITTI scan of ``scene``: points in the sensor's scan order and their labels.

    The sensor casts ``len(pitch_deg)`` rings of ``width`` rays, ring after ring from the top
    beam down, each ring counter-clockwise from azimuth ``pi / width`` (:func:`kitti_azimuths`);
    rays without a return are left out. Point ``i`` is therefore the ``i``-th pixel of
    ``np.flatnonzero(ranges > 0)`` over the ``(len(pitch_deg), width)`` grid of
    ``cast(scene, pitch_deg, kitti_azimuths(width), ...)``, and
    :func:`flic_cli.projection.project_points` recovers the rings from this order.

    Parameters
    ----------
    scene : what to scan (sensor frame).
    width : rays per ring (azimuth resolution 360 deg / width).
    pitch_deg : (H,) beam pitch in degrees, positive = downward, top beam first.
    noise : add the sensor's range noise, dropouts and remission noise (see
        :func:`~flic_cli.sample.cast`); default False: exact ranges, every hit within
        :data:`~flic_cli.sample.MAX_RANGE_M` returns.
    rng : source of the noise (None = ``np.random.default_rng(0)``); unused without noise.
    vehicle : boxes of the recording car that swallow rays (default: none, as in KITTI).

    Returns
    -------
    points : (N, 4) float32
        x, y, z in metres (sensor frame) and remission (0..1), in scan order.
    labels : (N,) uint32
        SemanticKITTI labels: semantic class | instance << 16.
    """
    az = kitti_azimuths(width)
    pitch = np.asarray(pitch_deg, dtype=np.float64).reshape(-1)
    ranges, sem, inst, rem = cast_full(scene, pitch, az, rng, vehicle, noise)
    el = -np.radians(pitch)[:, None]
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
    labels = encode(sem.reshape(-1), inst.reshape(-1))
    return pts.astype("<f4"), labels[keep].astype("<u4")


class MoosmannRender(NamedTuple):
    """A Moosmann frame and its ground truth (which the format itself cannot hold).

    Attributes
    ----------
    image : the range image as :class:`flic_cli.io.MoosmannDataset` loads it from the PNG (ranges
        quantised to the format's 2 mm, ``projection == "native"``, elevation from ``pitch_deg``).
    semantic : (H, W) uint16 SemanticKITTI class id per pixel, 0 where there is no return.
    instance : (H, W) uint16 instance id per pixel (things only), 0 elsewhere.
    """

    image: RangeImage
    semantic: np.ndarray
    instance: np.ndarray


def render_moosmann(
    scene: Scene,
    *,
    width: int = MOOSMANN_WIDTH,
    pitch_deg: np.ndarray = HDL64_PITCH_DEG,
    noise: bool = False,
    rng: np.random.Generator | None = None,
    vehicle: tuple[Box, ...] = (),
) -> MoosmannRender:
    """A Moosmann-style range image of ``scene``: column ``c`` looks at yaw
    ``+180 - 360 c / (width - 1)`` deg (:func:`moosmann_azimuths`), row ``r`` at ``pitch_deg[r]``.

    Parameters
    ----------
    scene : what to scan (sensor frame).
    width : number of columns.
    pitch_deg : (H,) beam pitch in degrees, positive = downward, top beam first.
    noise : add the sensor's noise and dropouts (default False: exact ranges).
    rng : source of the noise (None = ``np.random.default_rng(0)``); unused without noise.
    vehicle : boxes of the recording car that swallow rays; default none. The sample's Moosmann
        log uses :data:`~flic_cli.sample.EGO_VEHICLE`, which hides the beams steeper than 14 deg
        ahead and 11 deg behind.

    Returns
    -------
    MoosmannRender
        ``image.to_points()[image.point_pixel]`` are the points as the Moosmann loader gives them.
    """
    pitch = np.asarray(pitch_deg, dtype=np.float64).reshape(-1)
    ranges, sem, inst = cast(scene, pitch, moosmann_azimuths(width), rng, vehicle, noise=noise)
    # What the 16-bit PNG keeps: round(range * 500) / 500 (see flic_cli.io.write_png_range).
    stored = np.clip(np.rint(ranges.astype(np.float64) * RANGE_SCALE), 0, 65535)
    quantised = stored.astype(np.float32) / np.float32(RANGE_SCALE)
    return MoosmannRender(from_sensor_image(quantised, -np.radians(pitch)), sem, inst)
