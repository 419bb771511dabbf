"""The FLIC paper's ground extraction (paper section III-A)."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from numba import njit
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.component import STRICT
from flic_cli.ground.base import Ground, per_sensor
from flic_cli.range_image import RangeImage


@njit(cache=True)
def _paper_ground(
    ranges: np.ndarray,
    sin_a: np.ndarray,
    cos_a: np.ndarray,
    tan_lo: np.ndarray,
    tan_hi: np.ndarray,
    sin_el: np.ndarray,
    cos_el: np.ndarray,
    sensor_height: float,
    tan_slope: float,
) -> np.ndarray:
    """The paper's test for every cell. The pair (upper, lower) whose surface angle decides a cell
    is the cell and the one above it, or, for the top row and where the cell above is empty, the
    cell and the one below it, as in the paper's figure. Written so that every row's constants
    are loaded once and the per-cell work has no early exits (about 5x faster than a loop with
    ``continue``; same result)."""
    h, w = ranges.shape
    ground = np.zeros((h, w), dtype=np.bool_)
    for r in range(h):
        ser = sin_el[r]
        cer = cos_el[r]
        # pair with the cell above: lower row r
        sa, ca, lo_a, hi_a = sin_a[r], cos_a[r], tan_lo[r], tan_hi[r]
        # pair with the cell below: lower row r + 1
        has_below = r + 1 < h
        pb = r + 1 if has_below else r
        sb, cb, lo_b, hi_b = sin_a[pb], cos_a[pb], tan_lo[pb], tan_hi[pb]
        for c in range(w):
            d = ranges[r, c]
            up = ranges[r - 1, c] if r > 0 else np.float32(0.0)
            # height image first: above the 10 deg line from the wheel -> never ground
            below_line = d * ser <= -sensor_height + tan_slope * (d * cer)
            if up > 0.0:
                num = d * sa  # tan(beta) = num / den within [tan_lo, tan_hi]; den <= 0: >= 90 deg
                den = up - d * ca
                flat = den > 0.0 and lo_a * den <= num and num <= hi_a * den
            else:
                dn = ranges[pb, c] if has_below else np.float32(0.0)
                num = dn * sb
                den = d - dn * cb
                flat = dn > 0.0 and den > 0.0 and lo_b * den <= num and num <= hi_b * den
            ground[r, c] = d > 0.0 and below_line and flat
    return ground


def paper_tables(
    elevation: np.ndarray, max_slope_deg: float = 10.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per-row constants of the tan(beta) test: sin/cos of the beam gap, tan of the accepted band.

    For the pair (row p-1 above, row p), a horizontal surface gives beta equal to the depression
    angle of the upper beam; the cell is flat when beta is within +-max_slope of it.
    """
    el = np.asarray(elevation, dtype=np.float64)
    gap = np.zeros_like(el)
    gap[1:] = np.abs(el[:-1] - el[1:])
    depression = np.zeros_like(el)
    depression[1:] = -el[:-1]
    theta = np.radians(max_slope_deg)
    lo = np.clip(depression - theta, 0.0, np.radians(89.0))
    hi = np.clip(depression + theta, 0.0, np.radians(89.0))
    return np.sin(gap), np.cos(gap), np.tan(lo), np.tan(hi)


@per_sensor
def _row_constants(el: np.ndarray, max_slope_deg: float) -> tuple[np.ndarray, ...]:
    """:func:`paper_tables` and the sine and cosine of every row."""
    return (*paper_tables(el, max_slope_deg), np.sin(el), np.cos(el))


@dataclass(frozen=True, config=STRICT)
class PaperGround:
    """The paper's ground extraction as a :class:`flic_cli.ground.base.GroundRemover`.

    Attributes
    ----------
    max_slope_deg : surfaces within +-this of horizontal are ground candidates, degrees.
    height_slope_deg : slope of the height line from the wheel contact point, degrees (the paper:
        the same 10 deg); horizontal surfaces below it, car roofs beyond ~10 m, count as ground.
    sensor_height_m : sensor above the road, metres (KITTI and Moosmann: 1.73).
    """

    max_slope_deg: Annotated[float, Field(gt=0, lt=90, description="degrees")] = 10.0
    height_slope_deg: Annotated[float, Field(ge=0, lt=90, description="degrees")] = 10.0
    sensor_height_m: Annotated[float, Field(gt=0, description="metres")] = 1.73

    def extract(self, image: RangeImage, points: np.ndarray | None = None) -> Ground:
        """The ground pixels of ``image`` (:func:`paper_ground`); every point takes its pixel's
        decision."""
        mask = paper_ground(image, self.max_slope_deg, self.sensor_height_m, self.height_slope_deg)
        return Ground.from_mask(image, mask)


def paper_ground(
    image: RangeImage,
    max_slope_deg: float = PaperGround.max_slope_deg,
    sensor_height_m: float = PaperGround.sensor_height_m,
    height_slope_deg: float = PaperGround.height_slope_deg,
) -> np.ndarray:
    """Ground pixels by the paper's surface-angle test, keeping elevated horizontal surfaces.

    For every cell, the surface angle beta with the cell above is tested through
    ``tan(beta) = d2 sin(alpha) / (d1 - d2 cos(alpha))`` (no arctan; sin and cos precomputed per
    row). A cell is ground when beta is within ``max_slope_deg`` of the angle a horizontal surface
    would give, unless the height image puts it above the line that rises from the wheel contact
    point (``sensor_height_m`` below the sensor) at ``max_slope_deg``: car roofs and hoods are
    horizontal but stay.

    Parameters
    ----------
    image : the range image.
    max_slope_deg : accepted deviation from horizontal, degrees.
    sensor_height_m : height of the sensor above the road, metres.
    height_slope_deg : slope of the height line, degrees (the paper: the same 10 deg as
        ``max_slope_deg``). Horizontal surfaces below the line are ground: at 10 deg the line
        passes the sensor's height about 10 m out, so car roofs farther away count as ground.

    The defaults are those of :class:`PaperGround`.

    Returns
    -------
    (H, W) bool, True = ground. Empty pixels are never ground.
    """
    consts = _row_constants(image.elevation, float(max_slope_deg))
    sin_a, cos_a, tan_lo, tan_hi, sin_el, cos_el = consts
    return _paper_ground(
        image.ranges,
        sin_a,
        cos_a,
        tan_lo,
        tan_hi,
        sin_el,
        cos_el,
        float(sensor_height_m),
        float(np.tan(np.radians(height_slope_deg))),
    )
