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
residual is ``e = z - (z_g + m dr)``. A cell's ``(rho, z)`` is that of its pixel's nearest point
on a projected scan (:func:`pixel_geometry`: a row's elevation is only its beam's median, off by
several centimetres, as much as the bands below), its range along its row's elevation on a
sensor's own image.

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
   ``neighbour_px`` columns to its left or right (the nearest on each side), is at about its
   range (1 m) and height (``neighbour_band_m``, 8 cm), unless the cell is *stood on*: the next
   valid cell above it (within 2 rows) rises from it more steeply than ``foot_deg`` (the foot of
   a car, a person or a wall, whose lowest points are labelled as the object), or is nearer by
   0.3 m to ``under_m`` (ground seen under a car's body within its length, which the labels give
   to the car), nor when it lies *on a face*: the next valid cell below it (within 2 rows) is
   not ground and rises to it more steeply than ``face_deg`` (30 deg, as for the foot). A row
   across the side of a car, a hedge or a fence lies at one range and height, as ground does,
   and once a single cell of it was taken, the row test carried the ground along it (on the
   shared frames a parked car 23 m out lost 37 of its 241 points, 22 with the test; the ground
   precision goes from 95.48 to 95.84 %, ``results/ground/sweep_column_neighbours.csv``). Cells
   taken this way are not references themselves (no chains), and the column models do not
   follow them.
7. **Hidden points** (projected scans only: a sensor's own image holds one point per pixel). A
   pixel's range is that of its nearest point; on a projected KITTI scan about 9 % of the points
   lie behind the nearest one of their pixel, and every point of a pixel would share its
   decision. Ground seen just behind or under an object's lowest edge then stays with the
   object's pixel. So a point hidden behind its pixel's nearest point, in a pixel not taken, is
   ground when a pixel taken in the same row, at most ``neighbour_px`` columns away, is within
   1 m of its horizontal range and ``neighbour_band_m`` of its height (step 6's test, on the
   point itself; :meth:`ColumnGround.point_ground`). The clusterers then leave such points out
   (:func:`flic_cli.ground.base.extract_ground`).

8. **Held feet** (``hold_feet``). The cells step 6 refuses because something stands on them
   (the foot and under test) lie at the ground's height and range beside the objects: the
   labels give them to the object or to the ground, and no geometric rule tells which
   (``results/ground/oracle_counts.csv``). Left to the clusterers, they join parked cars to each
   other and to their surroundings along the ground, most in clusterers that reach across
   pixels (FLIC's neighbour reading, Bridge); taken as ground, they take the objects' lowest
   points, and cars at the minimum size fall under it. So they are *held*: the clusterers leave
   them out, and their points take the cluster of the cell standing on them (the one the foot
   test read) if it is within ``attach_m`` of it and not ground, and count towards its minimum
   size (:attr:`flic_cli.ground.base.Ground.attached`); a held cell under a held cell takes
   what that one takes. No held cell links anything. The kernel lists the held cells as step 6
   finds them; the ground decision and the metrics count them as not ground.

Empty pixels are never ground. Every cell is visited once (a few cells above it are read for
steps, seeds and the foot test), so the cost is linear in the image size. The image is not
wrapped at its left and right edges.

Parameters (see :class:`ColumnGround`) were chosen by the sweep in ``results/ground/`` on the
shared SemanticKITTI frames and the synthetic sample (``scripts/ground_study.py sweep``).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Annotated

import numpy as np
from numba import njit
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.bitwords import pack, trailing_zeros
from flic_cli.component import STRICT
from flic_cli.ground.base import Ground, per_sensor, points_left
from flic_cli.range_image import RangeImage

# Fixed constants of the algorithm (see the module docstring), with the values the sweep chose.
_BEHIND_M = 0.05  # a cell nearer than the last ground point by more than this is an object
_GAP_SLOPE_DEG = 5.0  # slope change allowed per metre of gap for a step
_SEED_SLOPE_DEG = 2.0  # seed tolerance grows with range at this slope
_FAR_DR_M = 0.5  # beyond this gap a continuation checks the cell above for an object
_RUN_CELLS = 3  # cells above that confirm a step or a seed
_RUN_MIN_CELLS = 2  # ...at least this many of them
_RUN_ROWS = 6  # ...found within this many rows
_RUN_JUMP = 0.3  # a cell farther than this share of rho ends the run (a depth jump); the floor
# of the per-row limits that follow the beam table (flic_cli.sensor_params.column_run_jumps)
_OCCLUDER_M = 0.15  # a cell above nearer by more than this (+2 % of rho) occludes the cell
_OCCLUDER_REL = 0.02
_GAIN_HEIGHT = 0.5  # alpha-beta filter of the ground model
_GAIN_GRADIENT = 0.3
_GAIN_BASE_M = 1.0  # the gradient update divides by max(dr, this)
_MAX_GRADIENT_DEG = 10.0
_BASE_DR_M = 1.0  # the base band applies within this distance beyond the last ground point
_ROW_DRHO_M = 1.0  # a row neighbour is at most this much nearer or farther
_FOOT_ROWS = 2  # the foot and face tests read the next valid cell within this many rows
_UNDER_MIN_M = 0.3  # a cell above nearer by more than this is an occluder (foot test)
_HIDDEN_M = 1e-3  # a point this much farther than its pixel's range is hidden behind it (7.)

# Layout of the parameter vector of :func:`_column_ground` (one array: one argument to type).
(_P_SENSOR, _P_NOISE, _P_TAN_CHANGE, _P_KERB, _P_MAX_STEP, _P_TAN_FLAT, _P_SEED_TOL,
 _P_BASE_BAND, _P_NB_PX, _P_NB_BAND, _P_TAN_FOOT, _P_UNDER, _P_ATTACH_SQ, _P_TAN_FACE,
 _P_LEN) = range(15)  # fmt: skip


@njit(inline="always")
def _cell(d: float, pz: float, se: float, ce: float, exact: bool) -> tuple[float, float]:
    """Horizontal range and height of a cell at range ``d`` (float32): from its nearest point's
    height ``pz`` when ``exact``, else along its row's elevation (sine ``se``, cosine ``ce``)."""
    if exact:
        return np.sqrt(max(d * d - pz * pz, np.float32(0.0))), pz
    return d * ce, d * se


def _geometry_kernel(exact: bool) -> Callable[..., None]:
    """The kernel that fills ``rho``, ``z`` of every pixel (:func:`_cell`; 0, 0 where empty)
    and ``up_rho``, ``up_z``, those of the next valid cell above it in its column (0, 0: none),
    row by row from the top, branch-free, so that every row runs as vector code. ``exact`` is
    fixed when the kernel is compiled (one kernel each way), so that no branch on it is left in
    the loop."""

    @njit(cache=True)
    def geometry(
        ranges: np.ndarray,
        point_z: np.ndarray,
        sin_el: np.ndarray,
        cos_el: np.ndarray,
        rho: np.ndarray,
        z: np.ndarray,
        up_rho: np.ndarray,
        up_z: np.ndarray,
    ) -> None:
        h, w = ranges.shape
        cur_rho = np.zeros(w, dtype=np.float32)  # the last valid cell of the rows so far
        cur_z = np.zeros(w, dtype=np.float32)
        for r in range(h):
            se = sin_el[r]
            ce = cos_el[r]
            for c in range(w):
                rv, zv = _cell(ranges[r, c], point_z[r, c], se, ce, exact)
                rho[r, c] = rv
                z[r, c] = zv
                cr = cur_rho[c]
                cz = cur_z[c]
                up_rho[r, c] = cr
                up_z[r, c] = cz
                valid = rv > 0.0
                cur_rho[c] = rv if valid else cr
                cur_z[c] = zv if valid else cz

    return geometry


#: :func:`_geometry_kernel` along the rows' elevation (False) and at the points' heights (True).
_GEOMETRY = {exact: _geometry_kernel(exact) for exact in (False, True)}


@njit(cache=True)
def _columns_row(
    rho_row: np.ndarray,
    z_row: np.ndarray,
    up_rho: np.ndarray,
    up_z: np.ndarray,
    g_rho: np.ndarray,
    g_z: np.ndarray,
    g_m: np.ndarray,
    last: np.ndarray,
    taken: np.ndarray,
    ask: np.ndarray,
    p: np.ndarray,
) -> None:
    """Steps 1, 2 and 5 for every cell of one row, and which cells need the cells above for
    step 3 or 4 (``ask``); updates the column models of the cells steps 2 takes.

    Every test is computed for every column and the results are selected without branches, so
    that the loop runs as vector code: which cells are ground is data that no branch predictor
    guesses. Step 2's test for the bottom row of a distant object reads the next valid cell
    above (``up_rho``, ``up_z``). The arithmetic is that of the scalar rule in the module
    docstring, in the same precision, so the masks are exactly the same: float32, that of the
    ranges, which fits twice as many columns into a vector as float64 (on the shared frames and
    the synthetic log no cell changed against float64, and the kernel took 20-30 % less)."""
    f = np.float32
    noise = f(p[_P_NOISE])
    tan_change = f(p[_P_TAN_CHANGE])
    step_k = noise + f(p[_P_KERB])
    max_step = f(p[_P_MAX_STEP])
    base_band = f(p[_P_BASE_BAND])
    tan_gap = f(np.tan(np.radians(_GAP_SLOPE_DEG)))
    tan_gap_3 = f(3.0) * tan_gap
    tan_seed = f(np.tan(np.radians(_SEED_SLOPE_DEG)))
    max_grad = f(np.tan(np.radians(_MAX_GRADIENT_DEG)))
    sensor_height = f(p[_P_SENSOR])
    seed_tol = f(p[_P_SEED_TOL])
    zero = f(0.0)
    behind = f(_BEHIND_M)
    far_dr = f(_FAR_DR_M)
    quarter = f(0.25)
    base_dr = f(_BASE_DR_M)
    gain_m = f(_GAIN_GRADIENT)
    gain_base = f(_GAIN_BASE_M)
    gain_z = f(_GAIN_HEIGHT)
    for c in range(rho_row.shape[0]):
        rho = rho_row[c]
        z = z_row[c]
        gr = g_rho[c]
        gz = g_z[c]
        gm = g_m[c]
        valid = rho > zero
        has = gr >= zero  # the column has ground
        dr = rho - gr
        in_front = dr < -behind  # 1.
        dr = dr if dr >= zero else zero
        e = z - (gz + gm * dr)
        band = noise + tan_change * dr
        live = valid & has & ~in_front
        cont = live & last[c] & (e >= -band) & (e <= band)  # 2.
        u = up_rho[c]
        stood_on = (dr > far_dr) & (u > zero) & (abs(u - rho) < quarter * dr)
        stood_on &= up_z[c] > z
        follow = cont & ~stood_on
        lim = step_k + tan_gap * dr
        lim = lim if lim <= max_step else max_step
        step = live & ~cont & (e >= -(step_k + tan_gap_3 * dr)) & (e <= lim)  # 3.
        es = z + sensor_height
        slim = seed_tol + tan_seed * rho
        seed = valid & ~has & (es >= -slim) & (es <= slim)
        base = live & (~cont | stood_on) & ~step & (dr < base_dr)  # 5.
        base &= (e >= -base_band) & (e <= base_band)
        m = gm + gain_m * e / max(dr, gain_base)
        m = min(max(m, -max_grad), max_grad)
        g_z[c] = (gz + gm * dr + gain_z * e) if follow else gz
        g_m[c] = m if follow else gm
        g_rho[c] = rho if follow else gr
        last[c] = last[c] & ~(valid & has & ~follow & ~step)
        taken[c] = follow | base
        ask[c] = step | seed


@njit(cache=True)
def _column_ground(
    rho_img: np.ndarray,
    z_img: np.ndarray,
    up_rho: np.ndarray,
    up_z: np.ndarray,
    p: np.ndarray,
    jumps: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The remover on one image given its geometry (:func:`pixel_geometry`): horizontal range
    and height of every pixel and of the next valid cell above it; ``p`` holds the parameters in
    the ``_P_*`` layout, ``jumps`` (H,) the run's depth-jump limit from each row to the next
    valid cell above (a share of ``rho``; :func:`flic_cli.sensor_params.column_run_jumps`).
    Returns the ground mask, the held cells (step 6's stood-on cells, step 8), and per held cell,
    in the order found (rows from the bottom), its flat pixel index and that of the cell
    standing on it if within ``attach_m`` of it, else -1.

    Every row, from the bottom, in three passes: steps 1, 2 and 5 for every column in vector
    code (:func:`_columns_row`); then the cells that step 3 or 4 asks about, one by one (the set
    bits of their packed flags), where the cells above decide; then step 6 on the gaps between
    consecutive cells taken so far (from the flips of the packed taken flags): the row test for
    every cell of a gap, the foot and face tests for the cells it hits. The columns are
    independent within a row, so the order of the passes does not change the mask
    (tests/test_ground_column.py pins it against the rule written cell by cell). The tests on
    the cells above are written out here rather than called as helpers: numba passes the images
    to a helper with atomic reference-count updates, which took a third of the time on scans
    with real ground. Indices into the images are unsigned, which keeps the generated code
    short."""
    sensor_height = np.float32(p[_P_SENSOR])
    noise32 = np.float32(p[_P_NOISE])
    noise = p[_P_NOISE]
    tan_change = np.float32(p[_P_TAN_CHANGE])
    base_band = np.float32(p[_P_BASE_BAND])
    tan_flat = p[_P_TAN_FLAT]
    nb_px = int(p[_P_NB_PX])
    nb_band = p[_P_NB_BAND]
    tan_foot = p[_P_TAN_FOOT]
    under = p[_P_UNDER]
    attach_sq = p[_P_ATTACH_SQ]
    tan_face = p[_P_TAN_FACE]
    h, w = rho_img.shape
    out = np.zeros((h, w), dtype=np.bool_)
    held = np.zeros((h, w), dtype=np.bool_)
    # the held cells and their standers, appended branch-free (only the written part is read);
    # a row appends at most w, so the buffers grow before a row that might not fit
    cells = np.empty(4 * w, dtype=np.int64)
    standers = np.empty(4 * w, dtype=np.int64)
    n_held = 0
    # the column models, in the precision of the ranges (float32: twice the vector width)
    g_rho = np.full(w, np.float32(-1.0))  # last ground point of the column (-1: none yet)
    g_z = np.zeros(w, dtype=np.float32)
    g_m = np.zeros(w, dtype=np.float32)  # ground gradient
    last = np.zeros(w, dtype=np.bool_)  # the column's previous valid cell was ground
    # the row's flags, padded to whole words: taken by steps 2-5, asking about the cells above
    nw = (w + 63) // 64
    taken = np.zeros(64 * nw, dtype=np.uint8)
    ask = np.zeros(64 * nw, dtype=np.uint8)
    taken_w = np.zeros(nw, dtype=np.uint64)
    ask_w = np.zeros(nw, dtype=np.uint64)
    flips = np.empty(w + 2, dtype=np.int64)  # columns where the row flips taken / not taken
    hits = np.empty(w, dtype=np.int64)  # the row's cells near a taken one (step 6's row test)
    for r in range(h - 1, -1, -1):
        rrow = rho_img[r]
        zrow = z_img[r]
        orow = out[r]
        hrow = held[r]
        if n_held + w > cells.size:
            cells = np.concatenate((cells, np.empty_like(cells)))
            standers = np.concatenate((standers, np.empty_like(standers)))
        _columns_row(rrow, zrow, up_rho[r], up_z[r], g_rho, g_z, g_m, last, taken, ask, p)
        pack(ask, ask_w)
        for k in range(nw):
            bits = ask_w[k]
            while bits:
                # Steps 3 (a step) and 4 (a seed): do the cells above continue a surface through
                # this one? s = 1 yes, 0 no, 2 no information (nothing above within reach, or the
                # next cell above is an occluder).
                uc = np.uintp(64 * k + trailing_zeros(bits))
                bits &= bits - np.uint64(1)
                rho = rrow[uc]
                z = zrow[uc]
                gr = g_rho[uc]
                is_step = gr >= 0.0
                dr = np.float32(0.0)
                band = np.float32(0.0)
                grad = np.float32(0.0)
                if is_step:
                    dr = rho - gr
                    if dr < 0.0:
                        dr = np.float32(0.0)
                    grad = g_m[uc]
                    e = z - (g_z[uc] + grad * dr)
                    band = noise32 + tan_change * dr
                else:
                    e = z + sensor_height
                s = -1
                n = 0
                prev = rho
                prev_jump = jumps[np.uintp(r)]
                run_rho = rho
                run_z = z
                lo = r - 1 - _RUN_ROWS
                if lo < -1:
                    lo = -1
                for ra in range(r - 1, lo, -1):
                    ua = np.uintp(ra)
                    ra_rho = rho_img[ua, uc]
                    if ra_rho <= 0.0:
                        continue
                    ra_z = z_img[ua, uc]
                    if ra_rho < prev - _BEHIND_M or ra_rho > prev + prev_jump * prev:
                        if n == 0:
                            s = 2 if ra_rho < prev - _OCCLUDER_M - _OCCLUDER_REL * prev else 0
                        break
                    ddr = max(ra_rho - rho, 0.0)
                    # every cell within a loose band, the end of the run within the flat band
                    if abs(ra_z - z - grad * ddr) > 2.0 * noise + tan_flat * ddr:
                        s = 0
                        break
                    prev = ra_rho
                    prev_jump = jumps[ua]
                    run_rho = ra_rho
                    run_z = ra_z
                    n += 1
                    if n >= _RUN_CELLS:
                        break
                if s < 0:
                    if n == 0:
                        s = 2
                    elif n < _RUN_MIN_CELLS:
                        s = 0
                    else:
                        ddr = max(run_rho - rho, 0.0)
                        s = 1 if abs(run_z - z - grad * ddr) <= noise + tan_flat * ddr else 0
                # no information: a step within both bands, a seed within the base band
                near = abs(e) <= (min(band, base_band) if is_step else base_band)
                if s == 1 or (s == 2 and near):
                    taken[uc] = True
                    g_z[uc] = z
                    g_rho[uc] = rho
                    last[uc] = True
                elif is_step:
                    last[uc] = False
                    # 5. base band
                    taken[uc] = dr < _BASE_DR_M and -base_band <= e <= base_band
        for c in range(w):
            orow[c] = taken[c]
        if nb_px <= 0:
            continue
        # 6. neighbours in the row: the refused cells between two consecutive taken cells a
        # and b (-1: none before or after), those within reach of a or of b. The gaps between
        # taken cells start and end where the row flips between taken and not (empty cells are
        # not taken: a gap may hold nothing valid).
        pack(taken, taken_w)
        n_flip = 0
        carry = np.uint64(0)
        for k in range(nw):
            t = taken_w[k]
            bits = t ^ ((t << np.uint64(1)) | carry)
            carry = t >> np.uint64(63)
            while bits:
                flips[np.uintp(n_flip)] = 64 * k + trailing_zeros(bits)
                n_flip += 1
                bits &= bits - np.uint64(1)
        if n_flip == 0:
            continue
        flips[np.uintp(n_flip)] = w  # a row that ends taken: its last gap is empty
        n_hits = 0
        for j in range(-1, n_flip + 1, 2):  # the gap from flip j (-1: the row's start)
            lo_q = flips[np.uintp(j)] if j >= 0 else 0
            a = lo_q - 1
            hi_q = flips[np.uintp(j + 1)] if j + 1 < n_flip else w
            b = hi_q if j + 1 < n_flip else -1
            if hi_q <= lo_q:
                continue
            end_a = min(a + nb_px + 1, hi_q) if a >= 0 else lo_q
            start_b = max(b - nb_px, end_a) if b >= 0 else hi_q
            a_rho = rrow[np.uintp(a)] if a >= 0 else np.float32(0.0)
            a_z = zrow[np.uintp(a)] if a >= 0 else np.float32(0.0)
            b_rho = rrow[np.uintp(b)] if b >= 0 else np.float32(0.0)
            b_z = zrow[np.uintp(b)] if b >= 0 else np.float32(0.0)
            for part in range(2):
                q0 = lo_q if part == 0 else start_b
                q1 = end_a if part == 0 else hi_q
                for q in range(q0, q1):
                    # branch-free: whether a cell is ground here is data that no branch
                    # predictor guesses; the cells that hit are listed for the tests below
                    uq = np.uintp(q)
                    rho = rrow[uq]
                    z = zrow[uq]
                    in_a = (a >= 0) & (q - a <= nb_px)
                    in_b = (b >= 0) & (b - q <= nb_px)
                    hit = in_a & (abs(rho - a_rho) <= _ROW_DRHO_M) & (abs(z - a_z) <= nb_band)
                    hit |= in_b & (abs(rho - b_rho) <= _ROW_DRHO_M) & (abs(z - b_z) <= nb_band)
                    hits[np.uintp(n_hits)] = q
                    n_hits += hit & (rho > 0.0)
        for j in range(n_hits):
            q = hits[np.uintp(j)]
            uq = np.uintp(q)
            rho = rrow[uq]
            z = zrow[uq]
            # a hit is ground unless it is stood on: the next valid cell above (within
            # _FOOT_ROWS rows) rises from it more steeply than tan_foot, or is nearer by
            # _UNDER_MIN_M to `under`
            found = False
            up_r = np.float32(0.0)
            up_h = np.float32(0.0)
            up_row = 0
            for k in range(1, _FOOT_ROWS + 1):
                ua = np.uintp(r - k if r >= k else 0)
                x = rho_img[ua, uq]
                now = ~found & (r >= k) & (x > 0.0)
                up_r = x if now else up_r
                up_h = z_img[ua, uq] if now else up_h
                up_row = r - k if now else up_row
                found |= now
            d = up_r - rho
            steep = (d > -under) if d < -_UNDER_MIN_M else (up_h - z > tan_foot * abs(d))
            stood = found & steep
            # nor on a face: the next valid cell below (within _FOOT_ROWS rows) is not ground
            # and rises to it more steeply than tan_face (a car's side, a hedge, a fence: rows
            # at one range and height, like ground)
            found_b = False
            dn_r = np.float32(0.0)
            dn_h = np.float32(0.0)
            dn_g = False
            for k in range(1, _FOOT_ROWS + 1):
                ub = np.uintp(r + k if r + k < h else h - 1)
                x = rho_img[ub, uq]
                now = ~found_b & (r + k < h) & (x > 0.0)
                dn_r = x if now else dn_r
                dn_h = z_img[ub, uq] if now else dn_h
                dn_g = out[ub, uq] if now else dn_g
                found_b |= now
            face = found_b & ~dn_g & (z - dn_h > tan_face * abs(rho - dn_r))
            orow[uq] = ~stood & ~face
            hrow[uq] = stood
            # step 8: the cell standing on it, if within attach_m
            dz = up_h - z
            close = d * d + dz * dz <= attach_sq
            cells[n_held] = r * w + q
            standers[n_held] = up_row * w + q if close else -1
            n_held += stood
    return out, held, cells[:n_held], standers[:n_held]


_ONE = np.ones(1, dtype=np.int32)  # the counts of a sensor's own image (not read)


@njit(cache=True)
def _attached(
    cells: np.ndarray,
    standers: np.ndarray,
    ground: np.ndarray,
    held: np.ndarray,
    counts: np.ndarray,
    native: bool,
    w: int,
) -> np.ndarray:
    """Step 8's (K, 3) table (:attr:`flic_cli.ground.base.Ground.attached`) from the
    kernel's held cells and their standers (rows from the bottom): a stander that is ground gives
    none; a held cell standing on a held cell takes that one's target. Walked backwards, the rows
    come top down, so the target of a held stander (the last held cell seen in its column:
    nothing valid lies between a cell and its stander) is known when it is read."""
    k = cells.size
    out = np.empty((k, 3), dtype=np.int64)
    last = np.empty(w, dtype=np.int64)  # target of the last held cell seen in every column
    inv_w = 1.0 / w
    for j in range(k - 1, -1, -1):
        p = cells[j]
        # p's column without an integer division (slow next to the rest of this loop)
        r = np.int64(p * inv_w)
        r += (r + 1) * w <= p
        r -= r * w > p
        c = p - r * w
        t = standers[j]
        if t >= 0:
            if ground[t]:
                t = -1
            elif held[t]:
                t = last[c]  # the stander is in the cell's column
        last[c] = t
        out[k - 1 - j, 0] = p
        out[k - 1 - j, 1] = t
        out[k - 1 - j, 2] = 1 if native else counts[p]
    return out


@njit(cache=True)
def _points_ground(
    ranges: np.ndarray,
    point_z: np.ndarray,
    sin_el: np.ndarray,
    cos_el: np.ndarray,
    exact: bool,
    mask: np.ndarray,
    point_pixel: np.ndarray,
    counts: np.ndarray,
    xyz: np.ndarray,
    reach: int,
    band: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """(N,) ground points: those of ground pixels, and by step 7 the points hidden behind their
    pixel's nearest point (farther than the pixel's range, by more than 1 mm) where that pixel
    is not ground; and, in the same pass, ``point_pixel`` and the (H * W,) ``counts`` without
    the points step 7 takes (their pixel -1, not counted; :func:`flic_cli.ground.base.
    leave_pixels`), and whether it took any."""
    h, w = ranges.shape
    flat = mask.reshape(h * w)
    rng = ranges.reshape(h * w)
    out = np.zeros(point_pixel.size, dtype=np.bool_)
    pix = point_pixel.copy()
    left = counts.copy()
    moved = False
    for i in range(point_pixel.size):
        p = point_pixel[i]
        if p < 0:
            continue
        if flat[p]:
            out[i] = True
            continue
        x = np.float64(xyz[i, 0])
        y = np.float64(xyz[i, 1])
        z = np.float64(xyz[i, 2])
        if np.sqrt(x * x + y * y + z * z) <= np.float64(rng[p]) + _HIDDEN_M:
            continue  # the pixel's nearest point (or as near)
        r = p // w
        c = p % w
        rho = np.sqrt(x * x + y * y)
        se = sin_el[r]
        ce = cos_el[r]
        for cc in range(max(c - reach, 0), min(c + reach + 1, w)):
            if mask[r, cc]:
                rv, zv = _cell(ranges[r, cc], point_z[r, cc], se, ce, exact)
                if abs(np.float64(rv) - rho) <= _ROW_DRHO_M and abs(np.float64(zv) - z) <= band:
                    out[i] = True
                    pix[i] = -1
                    left[p] -= 1
                    moved = True
                    break
    return out, pix, left, moved


@per_sensor
def _row_trig(el: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sine and cosine of every row as float32 (the precision of the ranges they multiply)."""
    return np.sin(el).astype(np.float32), np.cos(el).astype(np.float32)


def pixel_geometry(image: RangeImage, exact: bool = True) -> tuple[np.ndarray, ...]:
    """The geometry the remover works on: ``rho``, ``z`` (H, W) float32, the horizontal range
    and height of every pixel, metres (0 where empty); ``up_rho``, ``up_z``, those of the next
    valid cell above it (0: none).

    A projected scan (``exact`` and ``image.point_z`` known) gives every pixel the height of its
    nearest point: its row's elevation is only the median of its beam's, and the beams of a real
    sensor do not share one origin (on the shared SemanticKITTI frames a ground pixel's height
    along its row's elevation is off by more than 3 cm for half of them, 1st-99th percentile
    -21..+12 cm; ``scripts/ground_study.py heights``), as much as the remover's bands of 3-8 cm. A
    sensor's own image, or ``exact`` False: every pixel's range along its row's elevation.
    """
    h, w = image.shape
    out = tuple(np.empty((h, w), dtype=np.float32) for _ in range(4))
    ranges, point_z, sin_el, cos_el, exact = _cell_inputs(image, exact)
    _GEOMETRY[exact](ranges, point_z, sin_el, cos_el, *out)
    return out


def _cell_inputs(image: RangeImage, exact: bool) -> tuple:
    """``ranges, point_z, sin_el, cos_el, exact`` as :func:`_cell` reads them (``point_z`` is
    the ranges themselves, unread, where the rows' elevation is used)."""
    ranges = image.ranges
    if ranges.dtype != np.float32 or not ranges.flags.c_contiguous:
        ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    sin_el, cos_el = _row_trig(image.elevation)
    exact = bool(exact) and image.point_z is not None
    point_z = np.ascontiguousarray(image.point_z, dtype=np.float32) if exact else ranges
    return ranges, point_z, sin_el, cos_el, exact


@functools.lru_cache(maxsize=64)
def _param_vector(remover: ColumnGround) -> np.ndarray:
    """The parameters of ``remover`` in the ``_P_*`` layout of :func:`_column_ground`, angles as
    tangents (cached per setting)."""
    r = remover
    p = np.zeros(_P_LEN)
    p[_P_SENSOR] = r.sensor_height_m
    p[_P_NOISE] = r.noise_m
    p[_P_TAN_CHANGE] = np.tan(np.radians(r.slope_change_deg))
    p[_P_KERB] = r.kerb_m
    p[_P_MAX_STEP] = r.max_step_m
    p[_P_TAN_FLAT] = np.tan(np.radians(r.flat_deg))
    p[_P_SEED_TOL] = r.seed_tolerance_m
    p[_P_BASE_BAND] = r.base_band_m
    p[_P_NB_PX] = r.neighbour_px
    p[_P_NB_BAND] = r.neighbour_band_m
    p[_P_TAN_FOOT] = np.tan(np.radians(r.foot_deg))
    p[_P_UNDER] = r.under_m
    p[_P_ATTACH_SQ] = r.attach_m**2
    p[_P_TAN_FACE] = np.tan(np.radians(r.face_deg)) if r.face_deg < 90.0 else np.inf
    p.setflags(write=False)
    return p


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
    foot_deg : steeper rise to the cell above marks a foot (held), degrees.
    face_deg : steeper rise from the cell below (not ground) marks an object's face, which step
        6 does not take, degrees; 90 turns the test off.
    under_m : ground under a nearer occluder up to this far behind it is kept, metres.
    hidden_points : step 7, the points hidden behind their pixel's nearest point decided one by
        one (projected scans; a sensor's own image has none).
    hold_feet : step 8, the cells stood on (the foot and under test of step 6) are held out of
        the clustering and join the cluster of the cell that stands on them afterwards
        (False: they are clustered like any object cell).
    attach_m : a held cell joins the cell standing on it only within this distance, metres.
    run_jump : a step's or seed's confirming run ends at a cell farther than this share of the
        previous cell's ``rho`` (a depth jump), on every row; None (the default): per row, from
        the beam table, the growth of the ground's range to the next beam up plus a margin, at
        least 0.3 (:func:`flic_cli.sensor_params.column_run_jumps`; 0.3 on every row of the
        HDL-64E).
    point_heights : on projected scans, every pixel at its nearest point's height (False: at its
        range along its row's elevation, as on a sensor's own image; see
        :func:`pixel_geometry`).
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
    neighbour_band_m: Annotated[float, Field(ge=0, description="metres")] = 0.08
    foot_deg: Annotated[float, Field(gt=0, lt=90, description="degrees")] = 30.0
    face_deg: Annotated[float, Field(gt=0, le=90, description="degrees")] = 30.0
    under_m: Annotated[float, Field(ge=0, description="metres")] = 2.0
    hidden_points: bool = True
    point_heights: bool = True
    hold_feet: bool = True
    attach_m: Annotated[float, Field(gt=0, description="metres")] = 1.5
    run_jump: Annotated[float, Field(gt=0, le=10, description="share of rho")] | None = None

    def extract(self, image: RangeImage, points: np.ndarray | None = None) -> Ground:
        """The remover's decision on a scan (module docstring): the ground mask (steps 1-6),
        by step 7 the decision per point and the image the clusterers see without the points it
        takes, by step 8 the held cells and the cell standing on each, with their points counted
        in that image.

        Parameters
        ----------
        image : the scan's range image.
        points : (N, 3) the scan's points, pixel ``image.point_pixel[i]`` for point i; read by
            step 7 only (a projected scan), None elsewhere.
        """
        mask, held, cells, standers = _column_ground(
            *pixel_geometry(image, self.point_heights), _param_vector(self), self.run_jumps(image)
        )
        decided, clustered = None, image
        per_point = self.point_ground(image, points, mask)
        if per_point is not None:
            decided, clustered = per_point
        if not self.hold_feet:
            return Ground(mask, clustered, decided)
        # the held cells' points as the clusterers see them (step 7 may have taken some)
        native = clustered.one_point_per_pixel  # no counts to read
        counts = _ONE if native else np.ascontiguousarray(clustered.point_counts(), dtype=np.int32)
        attached = _attached(
            cells, standers, mask.reshape(-1), held.reshape(-1), counts.reshape(-1), native,
            image.shape[1],
        )  # fmt: skip
        return Ground(mask, clustered, decided, held, attached)

    def run_jumps(self, image: RangeImage) -> np.ndarray:
        """(H,) float64 depth-jump limit of the run above each row of ``image`` (a share of
        ``rho``): :attr:`run_jump` on every row, or where it is None, from the image's row
        elevations (:func:`flic_cli.sensor_params.column_run_jumps`, cached per beam table)."""
        if self.run_jump is not None:
            return np.full(image.shape[0], float(self.run_jump))
        from flic_cli.sensor_params import column_run_jumps

        return column_run_jumps(image.elevation, float(self.sensor_height_m))

    def point_ground(
        self, image: RangeImage, points: np.ndarray | None, mask: np.ndarray
    ) -> tuple[np.ndarray, RangeImage] | None:
        """(N,) bool ground points: those of ground pixels, and by step 7 (module docstring)
        the points hidden behind their pixel's nearest point where that pixel is not ground;
        and the image the clusterers see, without the points step 7 takes (made in the same
        pass; :func:`flic_cli.ground.base.leave_pixels`). None (every point takes its pixel's
        decision) without step 7 or on a sensor's own image, which has no hidden points.
        A step of :meth:`extract`, given ``mask``, the ground pixels."""
        if not self.hidden_points or image.one_point_per_pixel:
            return None
        if points is None:
            raise ValueError("step 7 (hidden_points) decides per point: it needs the points")
        on_ground, pix, counts, moved = _points_ground(
            *_cell_inputs(image, self.point_heights),
            np.ascontiguousarray(mask, dtype=np.bool_),
            np.ascontiguousarray(image.point_pixel, dtype=np.int64),
            np.ascontiguousarray(image.point_counts(), dtype=np.int32).reshape(-1),
            np.ascontiguousarray(points),
            int(self.neighbour_px),
            float(self.neighbour_band_m),
        )
        return on_ground, points_left(image, pix, counts, moved)
