"""Patchwork++ (Lee, Lim & Myung, IROS 2022) on the scan's points, as a ground remover.

Needs the optional extra ``patchworkpp`` (``pip install 'flic[patchworkpp]'``: the PyPI package
``pypatchworkpp``). Patchwork++ classifies points; the range image takes the decision of the point
that owns each pixel (the nearest one, see :func:`flic_cli.ground.base.pixel_mask`). For a
Moosmann log the points are the image's valid pixels, so the map is one to one.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Annotated

import numpy as np
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.component import STRICT
from flic_cli.errors import FlicInputError
from flic_cli.ground.base import Ground, pixel_mask
from flic_cli.range_image import RangeImage

#: What to install when the extra is missing.
INSTALL_HINT = "pip install 'flic[patchworkpp]'"


def _module():
    try:
        import pypatchworkpp
    except ImportError:
        raise FlicInputError(
            None,
            f"the patchworkpp ground remover needs the package pypatchworkpp ({INSTALL_HINT})",
        ) from None
    return pypatchworkpp


@contextmanager
def _quiet_stdout() -> Iterator[None]:
    """Silence file descriptor 1 (Patchwork++'s constructor prints a line to C++ stdout)."""
    sys.stdout.flush()
    saved = os.dup(1)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)
        os.close(devnull)


def patchworkpp_points(
    points: np.ndarray,
    sensor_height_m: float = 1.73,
    min_range_m: float = 2.7,
    max_range_m: float = 80.0,
) -> np.ndarray:
    """Per-point ground decision of Patchwork++ with its default parameters otherwise.

    A fresh estimator runs on every call, so the result depends on this scan alone (Patchwork++
    adapts its elevation and flatness thresholds over the scans it has seen; here every frame
    starts from the same state, and results do not depend on the order or the number of worker
    processes). Reflected-noise removal is off: it needs the remission, which flic does not read.

    Parameters
    ----------
    points : (N, 3+) float, metres, sensor frame (only x, y, z are used).
    sensor_height_m : sensor above the road, metres.
    min_range_m, max_range_m : Patchwork++'s range limits, metres (points outside are non-ground).

    Returns
    -------
    (N,) bool, True = ground.

    Raises
    ------
    FlicInputError
        When the optional package ``pypatchworkpp`` is not installed.
    """
    pw = _module()
    params = pw.Parameters()
    params.sensor_height = float(sensor_height_m)
    params.min_range = float(min_range_m)
    params.max_range = float(max_range_m)
    params.enable_RNR = False
    params.verbose = False
    with _quiet_stdout():
        est = pw.patchworkpp(params)
    out = np.zeros(points.shape[0], dtype=bool)
    if points.shape[0] == 0:
        return out
    est.estimateGround(np.ascontiguousarray(points[:, :3], dtype=np.float32))
    out[np.asarray(est.getGroundIndices(), dtype=np.int64)] = True
    return out


@dataclass(frozen=True, config=STRICT)
class PatchworkppGround:
    """Patchwork++ as a :class:`flic_cli.ground.base.GroundRemover` (optional extra).

    Attributes
    ----------
    sensor_height_m : sensor above the road, metres.
    min_range_m : points nearer than this (horizontal range) are non-ground, metres.
    max_range_m : points farther than this are non-ground, metres.
    """

    sensor_height_m: Annotated[float, Field(gt=0, description="metres")] = 1.73
    min_range_m: Annotated[float, Field(ge=0, description="metres")] = 2.7
    max_range_m: Annotated[float, Field(gt=0, description="metres")] = 80.0

    def check_installed(self) -> None:
        """Fail with the install hint when ``pypatchworkpp`` is missing (before the first frame)."""
        _module()

    def extract(self, image: RangeImage, points: np.ndarray) -> Ground:
        """The ground pixels: each pixel takes the decision of the point that owns it, and every
        point takes its pixel's (as the clusterers see them: Patchwork++'s own decision on the
        points hidden behind a pixel's nearest point is not used)."""
        ground = patchworkpp_points(
            points, self.sensor_height_m, self.min_range_m, self.max_range_m
        )
        return Ground.from_mask(image, pixel_mask(image, points, ground))
