"""Scan-line run, SLR (Zermas, Izzat, Papanikolopoulos: "Fast Segmentation of 3D Point Clouds:
a Paradigm on LiDAR Data for Autonomous Vehicle Applications", ICRA 2017, section III.B), on
the range image.

Each row of the image is a scan line. Along a line, consecutive measurements (skipping empty
and left-out pixels, the line closing round at 360 deg) closer than ``run_m`` form a run. Line
by line from the top, every measurement of a run looks for its nearest measurement in the line
above; when that is closer than ``merge_m``, the run takes that measurement's label. A run that
finds none gets a new label; a run that finds several merges them (the paper's label
equivalences, kept here in a union-find, so every merge reaches every run already labelled).
Distances are between the pixels' 3D points (range along the row's elevation and the column's
azimuth). Defaults: 0.5 m within a line, 1.0 m between lines, the ICCVW 2021 survey's
(Zhao, Zhang, Patel, "Towards Fast LiDAR Panoptic Segmentation without Training").

The nearest measurement above is searched exactly among the columns that can hold a point within
``merge_m`` (the azimuth window ``asin(merge_m / horizontal range)``), so the result is the
graph the paper defines: within-line links between consecutive measurements, one link from each
measurement to its nearest one above if close enough; the clusters are its connected
components.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, ClassVar

import numpy as np
from numba import njit
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.component import STRICT
from flic_cli.methods._peers import pixel_point_labels
from flic_cli.methods.base import ground_parts
from flic_cli.range_image import RangeImage

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground


@dataclass(frozen=True, config=STRICT)
class Slr:
    """Scan-line run as a :class:`flic_cli.methods.base.Method`.

    Attributes
    ----------
    run_m : consecutive measurements of a line closer than this are one run, metres.
    merge_m : a measurement joins its nearest measurement in the line above when closer, metres.
    min_size : smallest cluster kept, points.
    """

    run_m: Annotated[float, Field(gt=0, description="within a line, metres")] = 0.5
    merge_m: Annotated[float, Field(gt=0, description="between lines, metres")] = 1.0
    min_size: Annotated[int, Field(ge=1, description="smallest cluster kept, points")] = 100
    main_param: ClassVar[str] = "run_m"
    sweep_range: ClassVar[tuple[float, float, float]] = (0.1, 1.5, 0.1)
    slow: ClassVar[bool] = False
    sweep_label: ClassVar[str] = "SLR run distance [m]"

    def segment(self, image: RangeImage, points: np.ndarray, ground: Ground | None) -> np.ndarray:
        valid = image.ranges > 0
        left_out, _ = ground_parts(ground)  # ground and held pixels
        if left_out is not None:
            valid &= ~np.asarray(left_out, dtype=bool).reshape(valid.shape)
        pixel = slr_pixels(image, valid, self.run_m, self.merge_m)
        return pixel_point_labels(image, pixel, self.min_size, ground)


def slr_pixels(image: RangeImage, valid: np.ndarray, run_m: float, merge_m: float) -> np.ndarray:
    """(H*W,) int64 SLR label of every pixel (1..K, any numbering; 0 = not a measurement).

    Parameters
    ----------
    image : the range image (its pixels' 3D points are used).
    valid : (H, W) bool, the measurements to cluster.
    run_m, merge_m : thresholds, metres.
    """
    h, w = image.ranges.shape
    xyz = image.to_points().astype(np.float64).reshape(h, w, 3)
    return _slr(xyz, np.ascontiguousarray(valid), float(run_m), float(merge_m))


@njit(cache=True)
def _find(parent: np.ndarray, i: int) -> int:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True)
def _dist2(xyz: np.ndarray, r1: int, c1: int, r2: int, c2: int) -> float:
    dx = xyz[r1, c1, 0] - xyz[r2, c2, 0]
    dy = xyz[r1, c1, 1] - xyz[r2, c2, 1]
    dz = xyz[r1, c1, 2] - xyz[r2, c2, 2]
    return dx * dx + dy * dy + dz * dz


@njit(cache=True)
def _slr(xyz: np.ndarray, valid: np.ndarray, run_m: float, merge_m: float) -> np.ndarray:
    h, w = valid.shape
    run = np.zeros((h, w), dtype=np.int64)  # run id + 1 of every measurement
    parent = np.arange(h * w + 1)  # one union-find node per run (at most one per pixel)
    n_runs = 0
    run2 = run_m * run_m
    merge2 = merge_m * merge_m
    d_az = 2.0 * np.pi / w
    for r in range(h):
        # 1. the runs of line r
        first = -1
        prev = -1
        for c in range(w):
            if not valid[r, c]:
                continue
            if prev < 0 or _dist2(xyz, r, prev, r, c) >= run2:
                n_runs += 1
                run[r, c] = n_runs
            else:
                run[r, c] = run[r, prev]
            if first < 0:
                first = c
            prev = c
        if first >= 0 and prev != first and _dist2(xyz, r, prev, r, first) < run2:
            a = _find(parent, run[r, prev])
            b = _find(parent, run[r, first])
            if a != b:
                parent[max(a, b)] = min(a, b)
        if r == 0:
            continue
        # 2. every measurement's nearest measurement in line r - 1
        for c in range(w):
            if not valid[r, c]:
                continue
            hor = np.sqrt(xyz[r, c, 0] ** 2 + xyz[r, c, 1] ** 2)
            if merge_m >= hor:
                half = w // 2
            else:
                half = min(w // 2, int(np.ceil(np.arcsin(merge_m / hor) / d_az)) + 1)
            best = merge2
            best_c = -1
            for k in range(-half, half + 1):
                cc = (c + k) % w
                if valid[r - 1, cc]:
                    d = _dist2(xyz, r, c, r - 1, cc)
                    if d < best:
                        best = d
                        best_c = cc
            if best_c >= 0:
                a = _find(parent, run[r, c])
                b = _find(parent, run[r - 1, best_c])
                if a != b:
                    parent[max(a, b)] = min(a, b)
    out = np.zeros(h * w, dtype=np.int64)
    for r in range(h):
        for c in range(w):
            if valid[r, c]:
                out[r * w + c] = _find(parent, run[r, c])
    return out
