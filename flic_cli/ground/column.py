"""flic's own ground remover: column-wise ground tracking on the range image ("column").

What decides the score of a clusterer in the ground setting is the share of *object* points taken
as ground, and the ground left right beside objects (it joins them to their clusters). The paper's
remover tests every cell against the cell above it and a fixed height line, so it takes the inner,
near-horizontal surfaces of objects, their top outlines (where the cell above is far background)
and every roof beyond about 10 m. This remover instead follows the ground up every column, from
the nearest cell outwards, with a model of the local ground height, and takes a cell only where
it continues that ground.

The algorithm
-------------
The image is swept row by row from the bottom (nearest) row up; every column keeps its own ground
model: the last ground point ``(rho_g, z_g)`` (horizontal range and height, metres) and the local
gradient ``m`` (rise per metre). For a valid cell at ``(rho, z)`` with ``dr = rho - rho_g`` the
residual is ``e = z - (z_g + m dr)``.

1. **Behind.** A cell nearer than the last ground point (``dr < -5 cm``) stands in front of it:
   an object, never ground.
2. **Continuation.** When the previous valid cell of the column was ground and
   ``|e| <= noise_m + tan(slope_change_deg) dr``, the cell continues the ground. Beyond
   ``dr > 0.5 m`` (sparse rows far out) the cell is still refused when the next valid cell above
   stands on it (about the same ``rho``, higher): the bottom row of a distant object. The model
   follows the cell with a gain of 1/2 on the height and 0.3 on the gradient (an alpha-beta
   filter, gradient limited to +-10 deg), so that an object's side cannot be climbed in small
   steps.
3. **Step.** Otherwise (a kerb, the first ground behind an object, noise that broke the
   continuation) the cell may be up to ``kerb_m + tan(5 deg) dr`` (at most ``max_step_m``)
   above the model, and lower by any reasonable amount; it is taken only when the cells above it
   confirm a surface: the next ``3`` valid cells (within 6 rows, at least 2 of them, none nearer by
   more than 5 cm nor farther by more than 30 % of ``rho``) continue it within
   ``noise_m + tan(flat_deg) drho`` of the model's gradient. The model jumps to the cell (a kerb
   moves the ground up; the gradient is kept). A cell with nothing above it, or whose next cell
   above is clearly nearer (an occluder: ground under a car, seen through the gap beneath it), is
   taken when it lies within ``base_band_m`` of the model.
4. **Seed.** A column without ground yet (its lowest cells hit an object, or the recording car
   hides them) starts at the first cell within ``seed_tolerance_m + tan(2 deg) rho`` of the road
   ``sensor_height_m`` below the sensor, confirmed by the cells above as in 3 (with a level
   gradient), or, with nothing above, within ``base_band_m``.
5. **Base band.** A refused cell within ``base_band_m`` of the model and less than 1 m beyond the
   last ground point is ground too (the strip at the foot of objects, where a few centimetres of
   ground are labelled as the object or the object's lowest row is at road level), but the model
   does not follow it.
6. **Neighbours in the row.** The column steps leave ground behind where a column loses its
   model (a strip of parking between a grass verge and a car, terrain behind a low fence, the
   first rows of ground beside an object): the ground points that join objects to each other and
   to fences and vegetation in clusterers that reach across pixels (DBSCAN, Bridge). So, once a
   row is done, a refused cell is ground when a cell taken by steps 2-5 in the same row, at most
   ``neighbour_px`` columns to its left or right, is at about its range (1 m) and height
   (``neighbour_band_m``), unless the cell is *stood on*: the next valid cell above it (within 2
   rows) rises from it more steeply than ``foot_deg`` (the foot of a car, a person or a wall,
   whose lowest points are labelled as the object), or is nearer by 0.3 m to ``under_m``
   (ground seen under a car's body within its length, which the labels give to the car). Cells
   taken this way are not used as references themselves (no chains), and the column models do
   not follow them.

Empty pixels are never ground. Every cell is visited once (a few cells above it are read for
steps, seeds and the foot test), so the cost is linear in the image size. The image is not
wrapped at its left and right edges.

Parameters (see :class:`ColumnGround`) were chosen by the sweep in ``results/ground/`` on the
shared SemanticKITTI frames and the synthetic sample (``scripts/ground_sweep.py``).
"""

from __future__ import annotations

import functools
from typing import Annotated

import numpy as np
from numba import njit
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.config.component import STRICT
from flic_cli.range_image import RangeImage

# Fixed constants of the algorithm (see the module docstring), with the values the sweep chose.
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
_ROW_DRHO_M = 1.0  # a row neighbour is at most this much nearer or farther
_FOOT_ROWS = 2  # the foot test reads the next valid cell within this many rows above
_UNDER_MIN_M = 0.3  # a cell above nearer by more than this is an occluder (foot test)

# Layout of the parameter vector of :func:`_column_ground` (one array: one argument to type).
(_P_SENSOR, _P_NOISE, _P_TAN_CHANGE, _P_KERB, _P_MAX_STEP, _P_TAN_FLAT, _P_SEED_TOL,
 _P_BASE_BAND, _P_NB_PX, _P_NB_BAND, _P_TAN_FOOT, _P_UNDER, _P_LEN) = range(13)  # fmt: skip


@njit(cache=True)
def _surface_above(
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
    """Do the cells above (r, c) continue a surface through it? 1 yes, 0 no, 2 no information
    (nothing above within reach, or the next cell above is an occluder)."""
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
def _stood_on(
    rho_img: np.ndarray, z_img: np.ndarray, r: int, c: int, tan_foot: float, under: float
) -> bool:
    """Is (r, c) the foot of something (the next valid cell above, within ``_FOOT_ROWS`` rows,
    rises from it more steeply than ``tan_foot``) or under a near occluder (the cell above is
    nearer by ``_UNDER_MIN_M`` to ``under`` metres)?"""
    rho = rho_img[r, c]
    ra = r - 1
    while ra >= 0 and ra >= r - _FOOT_ROWS:
        ra_rho = rho_img[ra, c]
        if ra_rho > 0.0:
            d = ra_rho - rho
            if d < -_UNDER_MIN_M:
                return d > -under
            return z_img[ra, c] - z_img[r, c] > tan_foot * abs(d)
        ra -= 1
    return False


@njit(cache=True)
def _row_ok(rho: float, z: float, ref_rho: float, ref_z: float, nb_band: float) -> bool:
    """Is a cell at (rho, z) at the range and height of the row neighbour (ref_rho, ref_z)?"""
    return abs(rho - ref_rho) <= _ROW_DRHO_M and abs(z - ref_z) <= nb_band


@njit(cache=True)
def _column_ground(
    ranges: np.ndarray, sin_el: np.ndarray, cos_el: np.ndarray, p: np.ndarray
) -> np.ndarray:
    """The remover on one image; ``p`` holds the parameters in the ``_P_*`` layout."""
    sensor_height = p[_P_SENSOR]
    noise = p[_P_NOISE]
    tan_change = p[_P_TAN_CHANGE]
    kerb = p[_P_KERB]
    max_step = p[_P_MAX_STEP]
    tan_flat = p[_P_TAN_FLAT]
    seed_tol = p[_P_SEED_TOL]
    base_band = p[_P_BASE_BAND]
    nb_px = int(p[_P_NB_PX])
    nb_band = p[_P_NB_BAND]
    tan_foot = p[_P_TAN_FOOT]
    under = p[_P_UNDER]
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
    tan_gap = np.tan(np.radians(_GAP_SLOPE_DEG))
    tan_seed = np.tan(np.radians(_SEED_SLOPE_DEG))
    max_grad = np.tan(np.radians(_MAX_GRADIENT_DEG))
    step_k = noise + kerb
    out = np.zeros((h, w), dtype=np.bool_)
    g_rho = np.full(w, -1.0)  # last ground point of the column (-1: none yet)
    g_z = np.zeros(w)
    g_m = np.zeros(w)  # ground gradient
    last = np.zeros(w, dtype=np.bool_)  # the column's previous valid cell was ground
    pend = np.empty(w, dtype=np.int64)  # refused cells waiting for a right row neighbour
    for r in range(h - 1, -1, -1):
        rrow = rho_img[r]
        zrow = z_img[r]
        orow = out[r]
        ref_c = -(1 << 30)  # the last cell of this row taken by steps 2-5 (row neighbour)
        ref_rho = 0.0
        ref_z = 0.0
        n_pend = 0
        for c in range(w):
            rho = rrow[c]
            if rho <= 0.0:
                continue
            z = zrow[c]
            taken = False  # by steps 2-4 (the model follows)
            gr = g_rho[c]
            if gr >= 0.0:
                dr = rho - gr
                if dr >= -_BEHIND_M:  # else 1. in front of the ground: an object
                    if dr < 0.0:
                        dr = 0.0
                    gm = g_m[c]
                    e = z - (g_z[c] + gm * dr)
                    band = noise + tan_change * dr
                    if last[c] and -band <= e <= band:  # 2. continuation
                        taken = True
                        if dr > _FAR_DR_M:
                            for ra in range(r - 1, -1, -1):
                                ra_rho = rho_img[ra, c]
                                if ra_rho > 0.0:
                                    if abs(ra_rho - rho) < 0.25 * dr and z_img[ra, c] > z:
                                        taken = False
                                    break
                        if taken:
                            m = gm + _GAIN_GRADIENT * e / max(dr, _GAIN_BASE_M)
                            g_z[c] = g_z[c] + gm * dr + _GAIN_HEIGHT * e
                            g_m[c] = min(max(m, -max_grad), max_grad)
                    else:  # 3. step
                        lim = step_k + tan_gap * dr
                        if lim > max_step:
                            lim = max_step
                        if -(step_k + 3.0 * tan_gap * dr) <= e <= lim:
                            s = _surface_above(rho_img, z_img, r, c, rho, z, gm, noise, tan_flat)
                            if s == 1 or (s == 2 and abs(e) <= min(band, base_band)):
                                taken = True
                                g_z[c] = z
                    if not taken:
                        last[c] = False
                        # 5. base band: ground level just beyond the last ground point
                        if dr < _BASE_DR_M and -base_band <= e <= base_band:
                            orow[c] = True
                else:
                    last[c] = False
            else:  # 4. seed
                e = z + sensor_height
                lim = seed_tol + tan_seed * rho
                if -lim <= e <= lim:
                    s = _surface_above(rho_img, z_img, r, c, rho, z, 0.0, noise, tan_flat)
                    if s == 1 or (s == 2 and abs(e) <= base_band):
                        taken = True
                        g_z[c] = z
                if not taken:
                    last[c] = False
            if taken:
                g_rho[c] = rho
                last[c] = True
                orow[c] = True
            if nb_px <= 0:
                continue
            # 6. neighbours in the row
            if orow[c]:
                for k in range(n_pend - 1, -1, -1):  # refused cells waiting on the left
                    q = pend[k]
                    if c - q > nb_px:
                        break
                    if _row_ok(rrow[q], zrow[q], rho, z, nb_band):
                        if not _stood_on(rho_img, z_img, r, q, tan_foot, under):
                            orow[q] = True
                n_pend = 0
                ref_c = c
                ref_rho = rho
                ref_z = z
            elif c - ref_c <= nb_px and _row_ok(rho, z, ref_rho, ref_z, nb_band):
                if not _stood_on(rho_img, z_img, r, c, tan_foot, under):
                    orow[c] = True
                # (stood on: no row neighbour takes it)
            else:
                pend[n_pend] = c
                n_pend += 1
    return out


@functools.lru_cache(maxsize=32)
def _row_trig(elevation: bytes) -> tuple[np.ndarray, np.ndarray]:
    """Sine and cosine of every row, for one elevation table (given as its float64 bytes):
    computed once per sensor instead of once per frame."""
    el = np.frombuffer(elevation, dtype=np.float64)
    out = (np.sin(el), np.cos(el))
    for a in out:
        a.setflags(write=False)
    return out


@functools.lru_cache(maxsize=64)
def _param_vector(
    sensor_height_m: float,
    noise_m: float,
    slope_change_deg: float,
    kerb_m: float,
    max_step_m: float,
    flat_deg: float,
    seed_tolerance_m: float,
    base_band_m: float,
    neighbour_px: int,
    neighbour_band_m: float,
    foot_deg: float,
    under_m: float,
) -> np.ndarray:
    """The parameters in the ``_P_*`` layout of :func:`_column_ground` (cached per setting)."""
    p = np.zeros(_P_LEN)
    p[_P_SENSOR] = sensor_height_m
    p[_P_NOISE] = noise_m
    p[_P_TAN_CHANGE] = np.tan(np.radians(slope_change_deg))
    p[_P_KERB] = kerb_m
    p[_P_MAX_STEP] = max_step_m
    p[_P_TAN_FLAT] = np.tan(np.radians(flat_deg))
    p[_P_SEED_TOL] = seed_tolerance_m
    p[_P_BASE_BAND] = base_band_m
    p[_P_NB_PX] = neighbour_px
    p[_P_NB_BAND] = neighbour_band_m
    p[_P_TAN_FOOT] = np.tan(np.radians(foot_deg))
    p[_P_UNDER] = under_m
    p.setflags(write=False)
    return p


def column_ground(
    image: RangeImage,
    sensor_height_m: float = 1.73,
    noise_m: float = 0.03,
    slope_change_deg: float = 1.0,
    kerb_m: float = 0.2,
    max_step_m: float = 0.4,
    flat_deg: float = 15.0,
    seed_tolerance_m: float = 0.2,
    base_band_m: float = 0.05,
    neighbour_px: int = 10,
    neighbour_band_m: float = 0.05,
    foot_deg: float = 30.0,
    under_m: float = 2.0,
) -> np.ndarray:
    """Ground pixels by column-wise ground tracking (see the module docstring).

    Parameters
    ----------
    image : the range image.
    sensor_height_m : sensor above the road, metres (where columns start their ground).
    noise_m : height noise of the ground between neighbouring cells, metres.
    slope_change_deg : how fast the ground may bend, degrees per metre of ``dr``.
    kerb_m : largest step up onto a surface that continues flat (a kerb), metres.
    max_step_m : largest step up after a gap, metres (protects roofs, hoods, benches).
    flat_deg : largest deviation from the ground's gradient of the surface that confirms a step
        or a seed, degrees.
    seed_tolerance_m : a column's first ground cell lies within this of the road height (plus
        2 deg of slope times its range), metres.
    base_band_m : cells this close to the ground model just beyond it are ground, metres.
    neighbour_px : how far (columns) a row neighbour taken by the column steps may be; 0 turns
        step 6 off.
    neighbour_band_m : largest height difference to that row neighbour, metres.
    foot_deg : a cell whose next cell above rises from it more steeply than this is the foot of
        something standing on it and stays, degrees.
    under_m : a cell whose next cell above is nearer by 0.3 m to this is ground under a car's
        body (labelled as the car) and stays, metres.

    Returns
    -------
    (H, W) bool, True = ground. Empty pixels are never ground.
    """
    el = np.ascontiguousarray(image.elevation, dtype=np.float64)
    sin_el, cos_el = _row_trig(el.tobytes())
    ranges = image.ranges
    if ranges.dtype != np.float32 or not ranges.flags.c_contiguous:
        ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    params = _param_vector(
        float(sensor_height_m),
        float(noise_m),
        float(slope_change_deg),
        float(kerb_m),
        float(max_step_m),
        float(flat_deg),
        float(seed_tolerance_m),
        float(base_band_m),
        int(neighbour_px),
        float(neighbour_band_m),
        float(foot_deg),
        float(under_m),
    )
    return _column_ground(ranges, sin_el, cos_el, params)


@dataclass(frozen=True, config=STRICT)
class ColumnGround:
    """flic's column-wise ground tracking as a :class:`flic_cli.ground.base.GroundRemover`.

    Attributes
    ----------
    sensor_height_m : sensor above the road, metres (KITTI and Moosmann: 1.73).
    noise_m : height noise of the ground between neighbouring cells, metres.
    slope_change_deg : how fast the ground may bend, degrees per metre.
    kerb_m : largest step up onto a flat surface (a kerb), metres.
    max_step_m : largest step up after a gap (an object, missing cells), metres.
    flat_deg : the surface above a step or a seed is within this of the ground's slope, degrees.
    seed_tolerance_m : a column's first ground cell is within this of the road height, metres.
    base_band_m : cells within this of the ground just beyond it are ground, metres.
    neighbour_px : reach of step 6 (row neighbours), columns; 0 turns it off.
    neighbour_band_m : height band around a row neighbour, metres.
    foot_deg : steeper rise to the cell above marks a foot (kept), degrees.
    under_m : ground under a nearer occluder up to this far behind it is kept, metres.
    """

    sensor_height_m: Annotated[float, Field(gt=0, description="metres")] = 1.73
    noise_m: Annotated[float, Field(gt=0, description="metres")] = 0.03
    slope_change_deg: Annotated[float, Field(ge=0, lt=45, description="degrees per metre")] = 1.0
    kerb_m: Annotated[float, Field(ge=0, description="metres")] = 0.2
    max_step_m: Annotated[float, Field(ge=0, description="metres")] = 0.4
    flat_deg: Annotated[float, Field(gt=0, lt=60, description="degrees")] = 15.0
    seed_tolerance_m: Annotated[float, Field(gt=0, description="metres")] = 0.2
    base_band_m: Annotated[float, Field(ge=0, description="metres")] = 0.05
    neighbour_px: Annotated[int, Field(ge=0, le=1000, description="columns")] = 10
    neighbour_band_m: Annotated[float, Field(ge=0, description="metres")] = 0.05
    foot_deg: Annotated[float, Field(gt=0, lt=90, description="degrees")] = 30.0
    under_m: Annotated[float, Field(ge=0, description="metres")] = 2.0

    def __call__(self, image: RangeImage, points: np.ndarray | None = None) -> np.ndarray:
        """(H, W) bool ground mask of ``image`` (see :func:`column_ground`)."""
        return column_ground(
            image,
            self.sensor_height_m,
            self.noise_m,
            self.slope_change_deg,
            self.kerb_m,
            self.max_step_m,
            self.flat_deg,
            self.seed_tolerance_m,
            self.base_band_m,
            self.neighbour_px,
            self.neighbour_band_m,
            self.foot_deg,
            self.under_m,
        )
