"""Bridge: range-image clustering that reaches over holes and nearer occluders.

FLIC links a measurement to its four direct neighbours only, so an object falls apart wherever a
pixel between two of its measurements holds no return (dark paint, glass, grazing angles) or a
nearer occluder (a pole in front of a car). Bridge links every measurement to the *nearest
linkable measurement* in each direction, walking over empty pixels and over nearer
measurements, and stops where the scan shows free space beside it.

The graph
---------
Nodes: the pixels of ``mask`` with a range ``d > 0`` (a *measurement*). A measurement ``p`` at row
``r``, column ``c``, range ``d_p`` has the *link distance*

    t_p = max(threshold_m, d_p * sin(gamma_deg))

(fixed near the sensor; beyond ``threshold_m / sin(gamma)`` -- 10 m with the defaults -- it
grows with the range like the spacing of the beams, so that sparse far objects stay whole).

A *walk* from ``p`` in direction ``(dr, dc)`` visits ``q_k = (r + k dr, (c + k dc) mod W)`` for
``k = 1 .. K`` (columns wrap around: 360 deg sensor), with ``K = reach_px`` but no further than
the top row (``K <= r`` upwards) and less than a full turn (``K <= W - 1`` sideways):

- ``q_k`` is no node: if it holds a range (a pixel left out by ``mask``, e.g. ground) farther than
  ``d_p``, stop (free space, see below), else go on (a hole);
- ``|p - q_k| < t_p`` (3D distance, the law of cosines with the true angle between the two rays,
  each at its row's elevation and its own azimuth: the column's centre plus the row's azimuth
  offset, :attr:`flic_cli.range_image.RangeImage.azimuth_offset`): **edge p -- q_k**, stop;
- else ``d_q > d_p``: stop. The ray through ``q_k`` passed the depth of ``p`` without hitting
  anything, so the scan *sees free space* beside ``p`` in that direction: the gap between two
  people or between a car and the wall behind it is not jumped;
- else (``q_k`` is nearer: an occluder in front of ``p``): go on;
- a sideways walk also stops once it has passed more than ``open_holes_px`` *open holes*
  (empty pixels with no node near ``p``'s range above or below them in their column: section
  "Open holes" below).

Every measurement walks left ``(0, -1)`` and up ``(-1, 0)``. Unless both of these walks ended
with an edge at ``k = 1`` (``p`` lies inside a surface, and its diagonal neighbours are joined
through the adjacent ones), it also walks up-left ``(-1, -1)`` and up-right ``(-1, +1)``. So each
measurement has at most four edges. The clusters are the connected components; those with fewer
than ``min_size`` points (a pixel counts the points that fell into it) are dropped.

A walk also ends as soon as ``d_p sin(alpha_j) >= t_p`` for every ``j >= k``, with ``alpha_j`` the
angle between the rays of ``p`` and ``q_j``: every point of such a ray is at least
``d_p sin(alpha_j)`` from ``p`` (``alpha_j`` mostly grows with ``j``, but need not with azimuth
offsets), so nothing further on could be linked. This bound changes no edge; it only keeps the
walks short (the window shrinks with the range: at 20 m and 2048 columns a
horizontal walk ends after 11 columns).

With ``reach_px = 1``, ``gamma_deg = 0`` and ``level_tolerance = 0`` the graph is FLIC without
Map Connections plus the diagonal links of measurements on a surface's border.

Gaps beside (``fixed_side_gaps``, off by default)
-------------------------------------------------
Beyond 10 m the link distance ``d_p sin(gamma)`` lets a sideways walk (left, up-left, up-right)
reach over empty pixels as wide as ``gamma`` (0.70 m at 20 m): two people 0.5 m apart with
nothing measured between them (sky; the ground, removed in the "No Ground" setting) join.
With ``fixed_side_gaps`` an empty pixel ``e`` a sideways walk passes is an *open gap* when the
scan sees through its column: the first node above ``e`` or the first node below it in its
column lies beyond ``d_p + t_p``, and neither lies within ``t_p`` of ``d_p`` (a hole in p's
surface shows p's surface above or below it). Once a walk has passed an open gap it links only
within ``threshold_m`` (the walk's free-space rule, carried from the pixel walked to its
column). This splits such people at any range where something is seen behind them, but on the
50 shared KITTI frames far, sparse cars show such columns too and the rule costs 2.6 points of
IoU_mu there (results/bridge-cases/), so it is not the default.

Level surfaces (``level_tolerance`` 0.25, ``level_support = "beyond"`` by default)
----------------------------------------------------------------------------------
On a horizontal surface at height ``z < 0`` (sensor frame: below the sensor) the beams of rows
``r`` and ``r - k`` hit ``F = |z| |cot(e_{r-k}) - cot(e_r)|`` apart, the *footprint spacing*
(about ``d^2 de / |z|``: 0.5 m at 8 m, 2 m at 16 m for a hood 0.7 m below the sensor), at the
same height: a car's top or hood falls apart row by row under any fixed link distance, and the
car splits where the scan passes from its rear face onto its top. The *up* walk (only it) also
links p to the node ``q_k`` when q lies where the level surface through p meets q's beam,
within ``level_tolerance`` footprints along it, and within the margin:

    |z_q - z_p| < level_tolerance F |tan e_{r-k}|   and   |p - q_k| < L = level_margin F,
    L <= level_cap_m

(``z = d sin(e)``, ``F`` from p's height; a range error ``x`` along a beam of elevation ``e``
is a height error ``x |tan e|``), and, with ``level_support = "beyond"``, when the node right
above q is level with q by the same test: the level surface goes on beyond q. No level link
where either row's beam does not look down (a level surface above the sensor is an underside --
a canopy, a tree crown, a bridge -- never a thing's top), nor where ``L`` exceeds the cap (far
away, or near the sensor's height: the scan samples such a surface too sparsely to tell its
continuation from another object behind). The walk's other rules stay: it stops on free space
(a farther node not linked, a farther range outside the mask), and its bound uses
``max(t_p, level_cap_m)``.

Why the node beyond q: whatever stands behind p's edge (a second car's face, a person, a
motorcycle seen over a car's hood) is hidden by p's object below the line of sight over its
edge, so its first return above that edge, q, lies at p's height: level with p by the geometry
of occlusion, not by chance. But the node right above q lies on the same upright face, straight
above q, not on the level surface through q; on a car's top it lies farther along the top, level
with q. The node below p tells nothing of it: on a car's top it is level with p whatever stands
behind (``level_support = "either"``, the rule's first support, joined such objects:
results/bridge-cases/). What the scan cannot tell from a level surface -- a second object whose
*top* goes on at p's height within one footprint spacing (cars of one height parked bumper to
bumper) -- it joins. A deck the scan does not sample at all (beyond about 12 m a trunk lid or a
hood falls between two beams, and the face above it rises the deck's depth, 0.7 m, behind the
face below) gives the rule nothing to follow; a link over such steps joins the next parked car
and the wall a bicycle stands against as well (asked to keep the upper face within the lower
one's columns, still a bicycle and the piece of facade framed above it), and was measured and
not built (``scripts/bridge_deck.py``, results/bridge-cases/, "Decks"). The ground is removed
before clustering (by label or by the ground remover); where a remover leaves ground, level
links can join through it (with Bogoslavskyi's remover the shared frames lose 0.11 points,
results/ground/).

Measured (results/bridge-cases/, "Level surfaces beyond q"): against the Bridge without the
rule, the synthetic sample's moving cars (seen from behind or the front) go 69.4 -> 95.2 % IoU
(seed 0; FLIC 0 MC 91.7) and 89.4 -> 98.2 (seed 1), the samples gain 1.87, 0.34 and 0.39
points of IoU_mu (seeds 0, 1, 7; every class as before or better), every sensor profile's street
0.2-2.2, the 50 shared KITTI frames and the scenes are unchanged (+0.01, +0.07, not
significant); a van's hood one row deep is not joined to its cabin (no level node beyond q).
Without the support (``"none"``) or with ``"either"`` the sample lost 1.9 and 0.25 points
(measured on the Bridge without the hole limit: people, motorcycles and parked cars joined to
what stood behind them). The rule takes 1.16x
the time of the walk without it (1.31 ms per 870 x 64 frame with the ground extraction).

Open holes (``open_holes_px``; 4 by default)
--------------------------------------------
An empty pixel ``e`` that a sideways walk (left, up-left, up-right) of ``p`` passes is a *closed*
hole when the first node above ``e`` or the first node below it in its column lies within ``t_p``
of ``d_p`` (p's surface goes on around the hole: dark paint, a window with the roof above it),
else an *open* hole (between two people with the ground removed below and the facade or sky
above). With ``open_holes_px = n`` a walk that has passed more than ``n`` open holes stops;
closed holes and nearer occluders do not count, and the up walk is not limited. Unlike
``fixed_side_gaps`` it does not ask for a farther return in the hole's column, so it also
splits people with nothing behind them; unlike a smaller ``gamma_deg`` or a shorter ``reach_px``
(results/sweep/bridge/: 1.5 deg or 4 pixels cost the shared frames 2.5 and 3.8 points), it
leaves the far link distance on surfaces and over holes that the surface closes as it is.
``open_holes_px >= reach_px`` (or None) is no limit: a walk has at most ``reach_px`` steps.

Measured (results/bridge-cases/, "Open holes"): with n = 4 the scenes' people go from 75 to 98 %
IoU_mu (FLIC 0 MC 93), the synthetic sample gains 0.7 points, every sensor profile's street
gains up to 1.4 (the VLP-16's 75.7 -> 77.1, ahead of DBSCAN's 76.1), and the 50 shared KITTI
frames lose 0.18 (89.69 -> 89.51, still ahead of every other class-agnostic method); the walk
takes about 1.2-1.3x the time of the walk without the limit.

Seen through (``seen_through_m``; 4 m, with semantics only, by default)
-----------------------------------------------------------------------
Through a bus's or a tram's windows the scan sees its far side, 2-3.5 m behind the near side.
No walk links the two (the near side's edge sees a farther return: free space), so the far side
becomes a cluster of its own, framed in the image by the near side: roof above, body below,
pillars left and right. After the walks, every cluster B whose outline looks onto one nearer
cluster A in all four directions joins A:

- an *outline pixel* of B in a direction (left, right, up, down) is a node of B with no node of
  B within ``reach_px`` pixels that way (the top of B in its column, for up);
- it *looks onto* A when the first pixel that way, within ``reach_px``, holding a range no
  farther than its own (empty pixels and farther returns are seen through) is a node of A at
  most ``seen_through_m`` nearer, and, with semantics, of the outline pixel's class;
- B joins A when, in each of the four directions, more than half of B's outline pixels look onto
  A (clusters B and A as the walks left them; joins chain).

What the scan cannot tell from a vehicle's far side is an object standing behind a vehicle and
seen only through its windows (a motorcycle, a child, a low wall): the same frame, the same
depth. So the rule joins clusters of one class only, and only where the run has semantics
(``--semantics``: a network's or the oracle's; the near and far side of a bus are both bus, the
motorcycle behind a car is not car); without semantics it is off unless
``seen_through_agnostic``.

Measured (results/bridge-cases/, "Seen through"): on the 50 shared KITTI frames with oracle
semantics the bus's far side no longer makes 8 false positives (other-vehicle PQ 69.5 -> 99.0),
and the thing classes' PQ goes 52.34 -> 56.06 (ALPINE's 52.35, with k = 32 53.59; SLR's 55.16);
the samples' gains 0.13 (seeds 0 and 1); 3 m and 6 m give the same. Without semantics
(``seen_through_agnostic``) the shared frames gain 0.59 IoU_mu, but sample seed 0 loses 0.52
(its motorcycles behind parked cars, 30.5 -> 0), so it is not the default there.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Annotated, ClassVar, Literal, NamedTuple, get_args

import numpy as np
from numba import njit
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.bitwords import pack, trailing_zeros
from flic_cli.classes import learning_class
from flic_cli.component import STRICT
from flic_cli.methods.base import ground_parts, point_weights
from flic_cli.methods.connections import offset_input
from flic_cli.methods.criteria import distance_edge
from flic_cli.methods.engine import (
    attach,
    attached_input,
    kernel_inputs,
    label_row,
    number,
    pixel_output,
    point_output,
    run_buffers,
    union,
)
from flic_cli.range_image import RangeImage

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground

#: The most open holes a sideways walk crosses by default (module docstring, "Open holes").
OPEN_HOLES_PX = 4

#: The deepest a cluster seen through a nearer one of its class lies behind it and joins it, by
#: default, metres (module docstring, "Seen through").
SEEN_THROUGH_M = 4.0

#: The level link's tolerance by default, footprints (module docstring, "Level surfaces").
LEVEL_TOLERANCE = 0.25
#: The level link's reach by default, times the footprint spacing it follows (``level_margin``).
LEVEL_MARGIN = 1.5
#: No level link by default where that reach exceeds this, metres (``level_cap_m``).
LEVEL_CAP_M = 2.0

#: What a level link needs besides p and q (module docstring, "Level surfaces"): ``"none"``
#: nothing, ``"either"`` the node below p level with p or the node above q level with q,
#: ``"beyond"`` the node above q level with q (the default); the kernel takes the index.
LevelSupport = Literal["none", "either", "beyond"]
LEVEL_SUPPORT: tuple[str, ...] = get_args(LevelSupport)
#: The level link's support by default (module docstring, "Level surfaces").
LEVEL_SUPPORT_DEFAULT: LevelSupport = "beyond"

#: Walk directions (row step, column step): left, up, up-left, up-right (the order of the tables
#: of :func:`walk_tables`). Every walk goes towards earlier pixels in raster order, except left
#: walks across the 360 deg seam.
DIRECTIONS: tuple[tuple[int, int], ...] = ((0, -1), (-1, 0), (-1, -1), (-1, 1))


@njit(cache=True)
def walk_tables(elevation: np.ndarray, width: int, reach: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`walk_tables_offset` without azimuth offsets (every ray at its column's centre)."""
    return walk_tables_offset(elevation, np.zeros(elevation.size), width, reach)


@njit(cache=True)
def walk_tables_offset(
    elevation: np.ndarray, azimuth_offset: np.ndarray, width: int, reach: int
) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of the angle between the ray of (r, c) and the ray k steps away.

    Parameters
    ----------
    elevation : (H,) row elevations, radians.
    azimuth_offset : (H,) azimuth offset of every row, radians (a pixel's azimuth is its
        column's centre plus it, :attr:`flic_cli.range_image.RangeImage.azimuth_offset`): the
        angle is that between the two pixels' true directions.
    width : W, columns over 360 deg.
    reach : largest step k.

    Returns
    -------
    cos : (4, H, reach + 1) float64, cos of the angle, direction as in :data:`DIRECTIONS`.
    sin : (4, H, reach + 1) float64, the walk's bound: the smallest ``sin(alpha)`` (1 from
        90 deg on) of this and every later step, so that ``d_p * sin[k] >= t_p`` means no step
        from k on can be linked. Steps that leave the image (above row 0) get cos 1, sin 2.

    Notes
    -----
    The cosine is the dot product of the unit vectors ``(cos e cos a, cos e sin a, sin e)``,
    ``cos e_p cos e_q cos(a_q - a_p) + sin e_p sin e_q``. The azimuth falls by ``2 pi / W`` per
    column, so ``q`` k steps of ``dc`` columns from ``p`` has ``a_q - a_p = -k dc 2 pi / W +
    offset_q - offset_p``; where the two rows' offsets are equal (always without offsets) its
    cosine is taken as before the offsets came (``cos(k |dc| 2 pi / W)``), so that no edge of
    such an image changes.
    """
    h = elevation.size
    cos_t = np.ones((4, h, reach + 1))
    sin_t = np.full((4, h, reach + 1), 2.0)
    ce = np.cos(elevation)
    se = np.sin(elevation)
    h_step = 2.0 * np.pi / width
    ck = np.cos(np.arange(reach + 1) * h_step)
    for di in range(4):
        dr = DIRECTIONS[di][0]
        dc = DIRECTIONS[di][1]
        adc = abs(dc)
        for r in range(h):
            for k in range(1, reach + 1):
                r2 = r + k * dr
                if r2 < 0:
                    break
                off = azimuth_offset[r2] - azimuth_offset[r]
                ca = ck[k * adc] if off == 0.0 else np.cos(off - k * dc * h_step)
                # unit vectors (cos e cos a, cos e sin a, sin e): their dot product
                c = ce[r] * ce[r2] * ca + se[r] * se[r2]
                c = min(1.0, max(-1.0, c))
                cos_t[di, r, k] = c
                # every point of a ray at angle alpha from p's ray is at least d_p sin(alpha)
                # from p, or d_p once alpha >= 90 deg
                sin_t[di, r, k] = np.sqrt(1.0 - c * c) if c > 0.0 else 1.0
            # a walk may stop at k only if no later step can link either: suffix minimum (the
            # angle need not grow with k: offsets, or past 180 deg on very narrow images)
            for k in range(reach - 1, 0, -1):
                sin_t[di, r, k] = min(sin_t[di, r, k], sin_t[di, r, k + 1])
    return cos_t, sin_t


def _walk_row_kernel(gaps: bool, level_rule: bool, holes: bool) -> Callable[..., None]:
    """:func:`_walk_row` compiled with the tests of ``fixed_side_gaps`` (``gaps``) or without
    them, with those of the level rule (``level_rule``) or without them, with the open-holes count
    (``holes``) or without it.

    ``gaps``, ``level_rule`` and ``holes`` are constants of the compiled code, so a walk carries
    none of the loads, stores and selects of the rules it does not use: with the options compiled
    in but off, Bridge took 10-13 % longer per SemanticKITTI frame than before the options came
    (measured interleaved; see results/benchmark/revisions/README.md). (numba cannot hold one of
    these kernels in a variable, so the caller names each in a branch of its own.)
    """

    @njit(cache=True)
    def walk_row(
        r: int,
        w: int,
        on_w: np.ndarray,
        nodes: np.ndarray,
        raw: np.ndarray,
        labels: np.ndarray,
        parent: np.ndarray,
        cos_t: np.ndarray,
        sin_t: np.ndarray,
        threshold: float,
        sin_gamma: float,
        k_row: int,
        k_up: int,
        walks: np.ndarray,
        link_c: np.ndarray,
        link_q: np.ndarray,
        holed: np.ndarray,
        fixed_side_gaps: bool,
        above: np.ndarray,
        below: np.ndarray,
        level: LevelRule,
        max_open: int,
        n_open: np.ndarray,
    ) -> None:
        """The walks of row ``r`` past their first steps (module docstring); every link found
        merges two labels.

        ``on_w[di]``: packed flags of the nodes whose walk in direction ``di`` (left, up,
        up-left, up-right) goes on past its first step. ``nodes``: the node ranges (0 elsewhere),
        ``raw``: every range (a pixel outside the mask, e.g. ground, still shows free space),
        both flat. The walks of one direction advance together, step by step, over a list of the
        walks still going (``walks``); each step's tests are evaluated without a branch and the
        list is compacted, so the only branches are the loops' (and the options', constant along
        a walk). ``link_c``, ``link_q``: scratch for the links (column of p, flat index of q).
        ``holed``: scratch, whether a walk with a sideways step (left, up-left, up-right) has
        passed an open gap; with ``fixed_side_gaps`` such a walk links only within ``threshold``
        (module docstring, "Gaps beside"); ``above``, ``below``: the ranges of the first node
        above and below every pixel (:func:`_column_neighbours`). ``level``: the level-surface
        rule of the up walk (:func:`level_tables`, module docstring). ``max_open``: the most
        open holes a sideways walk crosses (-1 = no limit; module docstring, "Open holes"),
        ``n_open``: scratch, the open holes each walk has crossed. Without ``gaps``
        (:func:`_walk_row_kernel`) ``fixed_side_gaps`` is not read, without ``level_rule``
        ``level``, without ``holes`` ``max_open``.
        """
        one = np.uint64(1)
        level_on, sin_e, tan_e, spacing, level_tol, level_margin, level_cap, support = level
        row = r * w
        k_diag = min(k_up, k_row)
        for di in range(4):
            dr = 0 if di == 0 else -1
            dc = -1 if di == 0 or di == 2 else (0 if di == 1 else 1)
            kmax = k_row if di == 0 else (k_up if di == 1 else k_diag)
            if kmax < 2:
                continue
            side = gaps & fixed_side_gaps & (di != 1)
            lv_walk = level_rule & level_on & (di == 1)
            limit = holes & (max_open >= 0) & (di != 1)
            row_1 = (r + dr) * w
            m = 0
            for k in range(on_w.shape[1]):
                bits = on_w[di, k]
                while bits:
                    c = 64 * k + np.int64(trailing_zeros(bits))
                    bits &= bits - one
                    walks[m] = c
                    if gaps or holes:
                        c1 = c + dc
                        c1 += w if c1 < 0 else 0
                        c1 -= w if c1 >= w else 0
                        # the first step went on past an open gap (not a nearer node, not a hole
                        # in p's surface)
                        q1 = row_1 + c1
                        d1 = np.float64(nodes[row + c])
                        t1 = max(threshold, d1 * sin_gamma)
                        e1 = nodes[q1] <= 0.0
                        if gaps:
                            holed[m] = side and e1 and _open_gap(above, below, q1, d1, t1)
                        if limit:
                            # the first step crossed an open hole (no surface at p's range in
                            # its column); a walk past more than max_open of them stops
                            nh = np.int64(e1 & ~_closed(above, below, q1, d1, t1))
                            n_open[m] = nh
                            if nh > max_open:
                                continue
                    m += 1
            n_links = 0
            for step in range(2, kmax + 1):
                if m == 0:
                    break
                cos_k = cos_t[di, r, step]
                sin_k = sin_t[di, r, step]
                row_q = (r + step * dr) * w
                se_p = se_q = te_q = sp_k = 0.0
                if lv_walk:
                    r_q = r + step * dr
                    se_p, se_q, te_q = sin_e[r], sin_e[r_q], tan_e[r_q]
                    sp_k = spacing[r, step]
                going = 0
                for t in range(m):
                    c = walks[t]
                    h = holed[t] if side else False
                    d = np.float64(nodes[row + c])
                    t_far = max(threshold, d * sin_gamma)
                    tp = threshold if h else t_far
                    tp2 = tp * tp
                    c2 = c + step * dc
                    c2 += w if c2 < 0 else 0
                    c2 -= w if c2 >= w else 0
                    q = row_q + c2
                    dq = np.float64(nodes[q])
                    # the bound (nothing from here on can be linked), a link, free space beside p (a
                    # farther node, or a range beyond p outside the mask)
                    # (tp never grows along a walk; a level link is never longer than level_cap)
                    bound = d * sin_k >= (max(tp, level_cap) if lv_walk else tp)
                    linked = (dq > 0.0) & distance_edge(d, dq, cos_k, tp2)
                    if lv_walk:
                        lv = (dq > 0.0) & _level_edge(
                            d, dq, se_p, se_q, te_q, cos_k, sp_k, level_tol, level_margin, level_cap
                        )
                        if support and lv and not linked:  # (rare: only then look for support)
                            lv = _supported_level(
                                nodes, w, r, step, c, d, dq, cos_k, cos_t, sin_e, tan_e, spacing,
                                level_tol, level_margin, level_cap, support,
                            )  # fmt: skip
                        linked |= lv
                    free = (dq > d) | ((dq <= 0.0) & (raw[q] > d))
                    link_c[n_links] = c
                    link_q[n_links] = q
                    n_links += np.int64(linked) * (1 - np.int64(bound))
                    walks[going] = c
                    if side:
                        og = (dq <= 0.0) and _open_gap(above, below, q, d, t_far)
                        holed[going] = h | og
                    over = False
                    if limit:
                        nh = n_open[t]
                        if dq <= 0.0:
                            nh += np.int64(~_closed(above, below, q, d, t_far))
                        n_open[going] = nh
                        over = nh > max_open
                    going += 1 - np.int64(bound | linked | free | over)
                m = going
            for t in range(n_links):
                union(parent, labels[row + link_c[t]], labels[link_q[t]])

    return walk_row


#: The walks past the first steps: without any rule, with the open-holes count only, with it and
#: the level rule (Bridge's defaults), and with every rule's tests.
_walk_row_plain = _walk_row_kernel(False, False, False)
_walk_row_holes = _walk_row_kernel(False, False, True)
_walk_row_level = _walk_row_kernel(False, True, True)
_walk_row = _walk_row_kernel(True, True, True)


class LevelRule(NamedTuple):
    """The level-surface rule as the kernels take it (module docstring, "Level surfaces")."""

    on: bool
    #: (H,) sine of the row elevations
    sin_e: np.ndarray
    #: (H,) |tan| of the row elevations
    tan_e: np.ndarray
    #: (H, reach + 1) footprint spacing per metre of height, :func:`level_tables`
    spacing: np.ndarray
    #: footprints
    tolerance: float
    #: times the footprint spacing
    margin: float
    #: metres
    cap: float
    #: the support's index in :data:`LEVEL_SUPPORT`
    support: int


@njit(cache=True)
def level_tables(elevation: np.ndarray, reach: int) -> np.ndarray:
    """Footprint spacing per metre of height between the beams of rows ``r`` and ``r - k``.

    A level surface at height ``z < 0`` (sensor frame: below the sensor) is hit by the beam of
    elevation ``e < 0`` at the horizontal range ``z / tan(e)``, so the hits of rows ``r`` and
    ``r - k`` lie ``|z| |cot(e_{r-k}) - cot(e_r)|`` apart.

    Returns
    -------
    (H, reach + 1) float64, ``|cot(e_{r-k}) - cot(e_r)|``; 0 where the two beams do not both
    look down (an elevation of 0 or above: a level surface above the sensor is seen from below,
    a ceiling, a canopy, a crown, never a thing's top), or ``r - k < 0``: no level link there.
    """
    h = elevation.size
    out = np.zeros((h, reach + 1))
    for r in range(h):
        for k in range(1, min(reach, r) + 1):
            a = elevation[r]
            b = elevation[r - k]
            if a < 0.0 and b < 0.0:
                out[r, k] = abs(1.0 / np.tan(b) - 1.0 / np.tan(a))
    return out


@njit(cache=True, inline="always")
def _level_edge(
    d: float,
    dq: float,
    se_p: float,
    se_q: float,
    te_q: float,
    cos_k: float,
    spacing: float,
    tolerance: float,
    margin: float,
    cap: float,
) -> bool:
    """The level-surface link of the up walk (module docstring, "Level surfaces"): q (range
    ``dq``, ``k`` rows above p, same column) lies within ``tolerance`` footprints of where the
    level surface through p (range ``d``) meets q's beam (``te_q``: |tan| of its elevation),
    and closer to p than ``L = margin F``, ``L <= cap`` (``F = |z_p| spacing``, the footprint
    spacing of :func:`level_tables`, metres).
    """
    zp = d * se_p
    zq = dq * se_q
    foot = abs(zp) * spacing
    lim = margin * foot
    tol = tolerance * foot * te_q
    return (abs(zq - zp) < tol) & (lim <= cap) & distance_edge(d, dq, cos_k, lim * lim)


@njit(cache=True, inline="always")
def _supported_level(
    nodes: np.ndarray,
    w: int,
    r: int,
    k: int,
    c: int,
    d: float,
    dq: float,
    cos_k: float,
    cos_t: np.ndarray,
    sin_e: np.ndarray,
    tan_e: np.ndarray,
    spacing: np.ndarray,
    tol: float,
    margin: float,
    cap: float,
    support: int,
) -> bool:
    """The level link of p = (r, c) (range ``d``) to q = (r - k, c) (range ``dq``): a
    :func:`_level_edge`, and by ``support`` (:data:`LEVEL_SUPPORT`'s index) *supported*: 0 =
    always; 1 = the node right below p is level with p or the node right above q is level with
    q; 2 = the node right above q is level with q (each by :func:`_level_edge`; ``nodes`` flat,
    0 = no node)."""
    h = nodes.size // w
    if not _level_edge(
        d, dq, sin_e[r], sin_e[r - k], tan_e[r - k], cos_k, spacing[r, k], tol, margin, cap
    ):
        return False
    if support == 0:
        return True
    if support == 1 and r + 1 < h:
        db = np.float64(nodes[(r + 1) * w + c])
        if db > 0.0 and _level_edge(
            db, d, sin_e[r + 1], sin_e[r], tan_e[r], cos_t[1, r + 1, 1], spacing[r + 1, 1], tol,
            margin, cap,
        ):  # fmt: skip
            return True
    ra = r - k - 1
    if ra >= 0:
        da = np.float64(nodes[ra * w + c])
        if da > 0.0 and _level_edge(
            dq, da, sin_e[r - k], sin_e[ra], tan_e[ra], cos_t[1, r - k, 1], spacing[r - k, 1],
            tol, margin, cap,
        ):  # fmt: skip
            return True
    return False


@njit(cache=True, inline="always")
def _fill_row(
    d: np.ndarray,
    node: np.ndarray,
    rf: np.ndarray,
    sf: np.ndarray,
    use_skip: bool,
    row: int,
    w: int,
) -> None:
    """The node ranges ``d`` (0 where no node) and the flags ``node`` of the row starting at flat
    index ``row``, in one pass."""
    if use_skip:
        for c in range(w):
            x = rf[row + c]
            ok = (x > 0) & ~sf[row + c]
            d[c] = x if ok else np.float32(0.0)
            node[c] = ok
    else:
        for c in range(w):
            x = rf[row + c]
            d[c] = x if x > 0 else np.float32(0.0)
            node[c] = x > 0


@njit(cache=True, inline="always")
def _closed(above: np.ndarray, below: np.ndarray, q: int, d: float, tp: float) -> bool:
    """Whether the empty pixel ``q`` (flat index) is a hole in a surface at range ``d``: the
    first node above it or the first node below it in its column (``above``, ``below``: their
    ranges, 0 = none) lies within ``tp`` of ``d``."""
    a = np.float64(above[q])
    b = np.float64(below[q])
    return ((a > 0.0) & (abs(a - d) < tp)) | ((b > 0.0) & (abs(b - d) < tp))


@njit(cache=True, inline="always")
def _open_gap(above: np.ndarray, below: np.ndarray, q: int, d: float, tp: float) -> bool:
    """Whether the empty pixel ``q`` (flat index) is an open gap beside a node at range ``d``:
    not :func:`_closed` (a hole in p's surface shows that surface above or below it), and the
    first node above it or the first node below it in its column lies beyond ``d + tp`` (the
    scan sees through the gap's column)."""
    a = np.float64(above[q])
    b = np.float64(below[q])
    seen_through = (a > d + tp) | (b > d + tp)
    return (not _closed(above, below, q, d, tp)) and seen_through


@njit(cache=True)
def _column_neighbours(nodes: np.ndarray, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Range of the first node above and of the first node below every pixel in its column
    (0 = none), (H * W,) float32 each: one pass down the rows, one up."""
    above = np.empty(h * w, dtype=np.float32)
    below = np.empty(h * w, dtype=np.float32)
    last = np.zeros(w, dtype=np.float32)
    for r in range(h):
        row = r * w
        for c in range(w):
            above[row + c] = last[c]
            x = nodes[row + c]
            last[c] = x if x > 0 else last[c]
    last[:] = 0.0
    for r in range(h - 1, -1, -1):
        row = r * w
        for c in range(w):
            below[row + c] = last[c]
            x = nodes[row + c]
            last[c] = x if x > 0 else last[c]
    return above, below


@njit(cache=True, inline="always")
def _first_steps(
    link: np.ndarray,
    on: np.ndarray,
    d: np.ndarray,
    dq: np.ndarray,
    rq: np.ndarray,
    threshold: float,
    sin_gamma: float,
    cos_1: float,
    sin_1: float,
    further: bool,
) -> None:
    """The first step of every walk of a row, branch-free (LLVM vectorises it): ``link[c]``: the
    walk from node ``d[c]`` links to the node ``dq[c]`` one step away; ``on[c]``: it goes on to
    the next step (a hole or a nearer occluder there, and ``further``: the walk has more steps).
    ``rq``: the raw ranges one step away. Operations as in :func:`_walk_row`."""
    for c in range(d.size):
        dd = np.float64(d[c])
        q = np.float64(dq[c])
        t = dd * sin_gamma
        tp = threshold if threshold >= t else t
        ok = (dd > 0.0) & (dd * sin_1 < tp)
        linked = ok & (q > 0.0) & distance_edge(dd, q, cos_1, tp * tp)
        free = ((q > 0.0) & (q > dd)) | ((q <= 0.0) & (rq[c] > dd))
        link[c] = linked
        on[c] = ok & ~linked & ~free & further


@njit(cache=True)
def _first_steps_level(
    link: np.ndarray,
    on: np.ndarray,
    d: np.ndarray,
    dq: np.ndarray,
    rq: np.ndarray,
    threshold: float,
    sin_gamma: float,
    cos_1: float,
    sin_1: float,
    further: bool,
    nodes: np.ndarray,
    w: int,
    r: int,
    cos_t: np.ndarray,
    level: LevelRule,
    found: np.ndarray,
) -> None:
    """:func:`_first_steps` of the up walk of row ``r`` with the level-surface rule: a link also
    where :func:`_supported_level` holds; the walk's bound reaches ``max(t_p, cap)``. The level
    test itself runs branch-free over the row, flagging the level links that are no plain links
    in ``found`` (scratch, (W,) uint8); the support (``level_support``) is checked afterwards for
    those only."""
    _, sin_e, tan_e, spacing, tol, margin, cap, support = level
    se_p, se_q, te_q, sp = sin_e[r], sin_e[r - 1], tan_e[r - 1], spacing[r, 1]
    n_level = 0  # level links that are no plain links: only they need the support
    for c in range(d.size):
        dd = np.float64(d[c])
        q = np.float64(dq[c])
        t = dd * sin_gamma
        tp = threshold if threshold >= t else t
        ok = (dd > 0.0) & (dd * sin_1 < max(tp, cap))
        plain = ok & (q > 0.0) & distance_edge(dd, q, cos_1, tp * tp)
        lv = ok & (q > 0.0) & _level_edge(dd, q, se_p, se_q, te_q, cos_1, sp, tol, margin, cap)
        linked = plain | lv
        level_only = lv & ~plain
        found[c] = level_only
        n_level += np.int64(level_only)
        free = ((q > 0.0) & (q > dd)) | ((q <= 0.0) & (rq[c] > dd))
        link[c] = linked
        on[c] = ok & ~linked & ~free & further
    if support == 0 or n_level == 0:
        return
    for c in range(d.size):
        if not found[c]:
            continue
        dd = np.float64(d[c])
        q = np.float64(dq[c])
        if not _supported_level(
            nodes, w, r, 1, c, dd, q, cos_1, cos_t, sin_e, tan_e, spacing, tol, margin, cap, support
        ):
            link[c] = False  # a level link without support: the walk goes on unless free space
            free = q > dd
            on[c] = (not free) & further


@njit(cache=True)
def _bridge_components(
    ranges: np.ndarray,
    skip: np.ndarray,
    use_skip: bool,
    cos_t: np.ndarray,
    sin_t: np.ndarray,
    threshold: float,
    sin_gamma: float,
    reach: int,
    min_size: int,
    weights: np.ndarray,
    use_weights: bool,
    attached: np.ndarray,
    fixed_side_gaps: bool,
    level: LevelRule,
    max_open: int,
    seen_depth: float,
    classes: np.ndarray,
    use_classes: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Provisional label of every pixel (0 = no node) and the final label of each provisional
    label (0 = dropped): the connected components of the Bridge graph (module docstring); the
    held pixels of ``attached`` take the label standing on them
    (:func:`flic_cli.methods.connections.components`).

    The first step of every walk (left, up, up-left, up-right) is decided for a whole row at once
    (:func:`_first_steps`: link, stop or go on). The first-step links left and up are FLIC's
    direct connections with Bridge's test, so the rows are labelled by runs like FLIC's
    (:func:`flic_cli.methods.engine.label_row`); first-step diagonal links of the nodes not
    inside a surface (linked both left and up) merge labels from packed flags; the walks that go
    on are advanced step by step by :func:`_walk_row`. The labels are those of the pixel-by-pixel
    union-find this replaced (``tests/reference_kernels.py``).
    """
    h, w = ranges.shape
    n = h * w
    rf = ranges.reshape(n)
    sf = skip.reshape(skip.size)  # a (1, 1) stand-in when not use_skip
    wf = weights.reshape(weights.size)
    nodes = np.empty(n, dtype=np.float32)  # node ranges, 0 elsewhere
    (
        labels, parent, size, node, left, up, node_w, left_w, left_up_w, up_w, starts, ends, acc
    ) = run_buffers(n, w)  # fmt: skip
    nw = node_w.size - 1
    pad = 64 * nw + 8
    left_on = np.zeros(pad, dtype=np.uint8)  # the left walk goes past its first step
    up_on = np.zeros(pad, dtype=np.uint8)
    ul = np.zeros(pad, dtype=np.uint8)  # the first step up-left links
    ul_on = np.zeros(pad, dtype=np.uint8)  # ... or goes on
    ur = np.zeros(pad, dtype=np.uint8)  # the same up-right
    ur_on = np.zeros(pad, dtype=np.uint8)
    ul_link = np.zeros(pad, dtype=np.uint8)  # a diagonal first step's link to merge
    ur_link = np.zeros(pad, dtype=np.uint8)
    ul_go = np.zeros(pad, dtype=np.uint8)  # a diagonal walk to go on with
    ur_go = np.zeros(pad, dtype=np.uint8)
    level_only = np.zeros(w, dtype=np.uint8)  # an up link at the first step that is level only
    ul_w = np.zeros(nw, dtype=np.uint64)
    ur_w = np.zeros(nw, dtype=np.uint64)
    on_w = np.zeros((4, nw), dtype=np.uint64)
    walks = np.empty(w, dtype=np.int64)
    link_c = np.empty(w, dtype=np.int64)
    link_q = np.empty(w, dtype=np.int64)
    holed = np.empty(w, dtype=np.bool_)
    holes = np.empty(w, dtype=np.int64)
    one = np.uint64(1)
    k_row = min(reach, w - 1)
    n_labels = np.uint64(0)
    options = fixed_side_gaps or level.on or max_open >= 0
    # With an option on, all rows first: its walks look up and down the column of a gap (a hole
    # in a surface?) and level links at the row below; the default walks look at earlier rows
    # only, so each row is filled as it comes (one pass for ranges and flags).
    if options:
        for r in range(h):
            _fill_row(nodes[r * w : (r + 1) * w], node, rf, sf, use_skip, r * w, w)
    if fixed_side_gaps or max_open >= 0:
        col_above, col_below = _column_neighbours(nodes, h, w)
    else:
        col_above = col_below = np.zeros(1, dtype=np.float32)
    for r in range(h):
        row = r * w
        d = nodes[row : row + w]
        raw = rf[row : row + w]
        _fill_row(d, node, rf, sf, use_skip, row, w)  # (with an option on: again, the same)
        k_up = min(reach, r)
        if k_row >= 1:
            _first_steps(
                left[1:w], left_on[1:w], d[1:], d[:-1], raw[:-1], threshold, sin_gamma,
                cos_t[0, r, 1], sin_t[0, r, 1], k_row >= 2,
            )  # fmt: skip
            # column 0: its first step left crosses the seam (a link there is merged below)
            _first_steps(
                left[:1], left_on[:1], d[:1], d[w - 1 :], raw[w - 1 :], threshold, sin_gamma,
                cos_t[0, r, 1], sin_t[0, r, 1], k_row >= 2,
            )  # fmt: skip
        seam = left[0]
        left[0] = 0
        k_diag = min(k_up, k_row)
        if k_up >= 1:
            above = nodes[row - w : row]
            raw_above = rf[row - w : row]
            if level.on:
                _first_steps_level(
                    up[:w], up_on[:w], d, above, raw_above, threshold, sin_gamma,
                    cos_t[1, r, 1], sin_t[1, r, 1], k_up >= 2, nodes, w, r, cos_t, level,
                    level_only,
                )  # fmt: skip
            else:
                _first_steps(
                    up[:w], up_on[:w], d, above, raw_above, threshold, sin_gamma,
                    cos_t[1, r, 1], sin_t[1, r, 1], k_up >= 2,
                )  # fmt: skip
        if k_diag >= 1:  # (w > 1) the diagonal neighbours, across the seam at both ends
            c1, s1, on = cos_t[2, r, 1], sin_t[2, r, 1], k_diag >= 2
            _first_steps(
                ul[1:w], ul_on[1:w], d[1:], above[:-1], raw_above[:-1], threshold, sin_gamma,
                c1, s1, on,
            )  # fmt: skip
            _first_steps(
                ul[:1], ul_on[:1], d[:1], above[w - 1 :], raw_above[w - 1 :], threshold,
                sin_gamma, c1, s1, on,
            )  # fmt: skip
            c1, s1 = cos_t[3, r, 1], sin_t[3, r, 1]
            _first_steps(
                ur[: w - 1], ur_on[: w - 1], d[:-1], above[1:], raw_above[1:], threshold,
                sin_gamma, c1, s1, on,
            )  # fmt: skip
            _first_steps(
                ur[w - 1 : w], ur_on[w - 1 : w], d[w - 1 :], above[:1], raw_above[:1],
                threshold, sin_gamma, c1, s1, on,
            )  # fmt: skip
        n_labels = label_row(
            r, w, n_labels, d, node, left, up, node_w, left_w, left_up_w, up_w, starts, ends, acc,
            labels, parent, size, wf, use_weights,
        )  # fmt: skip
        left_w, left_up_w = left_up_w, left_w
        if seam:
            union(parent, labels[row], labels[row + w - 1])
        # The diagonal walks of nodes not inside a surface (linked left and up at the first
        # step): links at their first step are merged here; walks going on past their first
        # step, in any direction, are walked one by one.
        if k_diag >= 1:
            for c in range(w):
                out = ~(left[c] & up[c])  # (left[0] = 0: fixed below)
                ul_link[c] = ul[c] & out
                ur_link[c] = ur[c] & out
                ul_go[c] = ul_on[c] & out
                ur_go[c] = ur_on[c] & out
            out = ~(seam & up[0])
            ul_link[0] = ul[0] & out
            ur_link[0] = ur[0] & out
            ul_go[0] = ul_on[0] & out
            ur_go[0] = ur_on[0] & out
            pack(ul_link[: 64 * nw], ul_w)
            pack(ur_link[: 64 * nw], ur_w)
            pack(ul_go[: 64 * nw], on_w[2])
            pack(ur_go[: 64 * nw], on_w[3])
            for k in range(nw):
                bits = ul_w[k]
                while bits:
                    c = 64 * k + np.int64(trailing_zeros(bits))
                    bits &= bits - one
                    j = row - w + (c - 1 if c > 0 else w - 1)
                    union(parent, labels[row + c], labels[j])
                bits = ur_w[k]
                while bits:
                    c = 64 * k + np.int64(trailing_zeros(bits))
                    bits &= bits - one
                    j = row - w + (c + 1 if c < w - 1 else 0)
                    union(parent, labels[row + c], labels[j])
        pack(left_on[: 64 * nw], on_w[0])
        pack(up_on[: 64 * nw], on_w[1])
        if fixed_side_gaps:
            _walk_row(
                r, w, on_w, nodes, rf, labels, parent, cos_t, sin_t, threshold, sin_gamma,
                k_row, k_up, walks, link_c, link_q, holed, fixed_side_gaps, col_above, col_below,
                level, max_open, holes,
            )  # fmt: skip
        elif level.on:
            _walk_row_level(
                r, w, on_w, nodes, rf, labels, parent, cos_t, sin_t, threshold, sin_gamma,
                k_row, k_up, walks, link_c, link_q, holed, fixed_side_gaps, col_above, col_below,
                level, max_open, holes,
            )  # fmt: skip
        elif max_open >= 0:
            _walk_row_holes(
                r, w, on_w, nodes, rf, labels, parent, cos_t, sin_t, threshold, sin_gamma,
                k_row, k_up, walks, link_c, link_q, holed, fixed_side_gaps, col_above, col_below,
                level, max_open, holes,
            )  # fmt: skip
        else:
            _walk_row_plain(
                r, w, on_w, nodes, rf, labels, parent, cos_t, sin_t, threshold, sin_gamma,
                k_row, k_up, walks, link_c, link_q, holed, fixed_side_gaps, col_above, col_below,
                level, max_open, holes,
            )  # fmt: skip
    if seen_depth > 0.0:
        _seen_through(
            labels, parent, nodes, rf, classes, use_classes, h, w, np.int64(n_labels), reach,
            seen_depth,
        )  # fmt: skip
    attach(labels, size, attached)
    return labels[:n], number(parent, size, np.int64(n_labels), min_size)


@njit(cache=True, inline="always")
def _look(
    nodes: np.ndarray, raw: np.ndarray, root: np.ndarray, cls: np.ndarray, use_cls: bool,
    i: int, b: int, dr: int, dc: int, h: int, w: int, limit: int, depth: float,
) -> int:  # fmt: skip
    """The cluster that pixel ``i`` of cluster ``b`` looks onto in direction ``(dr, dc)``, within
    ``limit`` steps: -1 if a node of ``b`` lies there (``i`` is not on ``b``'s outline in that
    direction); else the cluster (``root``: the cluster of every pixel, 0 = none) of the first
    pixel that holds a range no farther than ``i``'s (empty pixels and farther returns are seen
    through) if it is at most ``depth`` nearer (and, with ``use_cls``, of ``i``'s class: ``cls``,
    the class of every pixel); else 0 (none, or a return left out: ground)."""
    d = np.float64(nodes[i])
    r = i // w
    c = i - r * w
    out = 0
    found = False
    for k in range(1, limit + 1):
        r2 = r + k * dr
        if r2 < 0 or r2 >= h:
            break
        c2 = c + k * dc
        c2 += w if c2 < 0 else 0
        c2 -= w if c2 >= w else 0
        j = r2 * w + c2
        a = root[j]
        if a == b:
            return -1
        x = np.float64(raw[j])
        if found or x <= 0.0 or x > d:
            continue
        found = True
        same = (not use_cls) or cls[j] == cls[i]
        out = a if d - x <= depth and same else 0
    return out


@njit(cache=True)
def _seen_through(
    labels: np.ndarray, parent: np.ndarray, nodes: np.ndarray, raw: np.ndarray, cls: np.ndarray,
    use_cls: bool, h: int, w: int, n_labels: int, limit: int, depth: float,
) -> None:  # fmt: skip
    """Merge every cluster seen through a nearer one (module docstring, "Seen through").

    ``labels``: provisional label of every pixel, ``parent``: their union-find forest (flattened
    here: ``parent[l]`` becomes the root of ``l``), ``nodes`` / ``raw``: node and raw ranges,
    flat; ``cls``: the class of every pixel, read with ``use_cls`` (:func:`_look`). Every node
    looks in each direction (left, right, up, down; ``limit`` steps, sideways less than a full
    turn): it is an *outline pixel* of its cluster there unless a node of the cluster lies
    within the look, and looks onto a cluster or none. Per direction the cluster most looked onto
    is found by majority vote (Boyer-Moore) over the outline pixels, then its looks are counted.
    A cluster B whose four directions look onto the same cluster A, each from more than half of
    its outline pixels, joins A; the decisions are all taken on the clusters as the walks left
    them. The directions are taken in turn, each only for the clusters that the ones before
    left in question (left and right first: their looks run along the rows in memory), and a
    node whose next pixel holds a node of its own cluster is no outline pixel without a look.
    """
    n = h * w
    for lab in range(1, n_labels + 1):
        parent[lab] = parent[parent[lab]]
    root = np.empty(n, dtype=np.int64)  # the cluster of every pixel, 0 = no node
    for i in range(n):
        root[i] = parent[labels[i]] if nodes[i] > 0.0 else 0
    m = n_labels + 1
    alive = np.ones(m, dtype=np.bool_)  # still a candidate
    target = np.zeros(m, dtype=np.int64)  # the cluster looked onto
    cand = np.zeros(m, dtype=np.int64)
    votes = np.zeros(m, dtype=np.int64)
    total = np.zeros(m, dtype=np.int64)
    out_b = np.empty(n, dtype=np.int64)  # cluster of every outline pixel of the direction
    out_a = np.empty(n, dtype=np.int64)  # the cluster it looks onto (0: none)
    for di in range(4):
        dr = 0 if di < 2 else (-1 if di == 2 else 1)
        dc = -1 if di == 0 else (1 if di == 1 else 0)
        steps = min(limit, w - 1) if di < 2 else limit  # sideways: less than a full turn
        cand[:] = 0
        votes[:] = 0
        total[:] = 0
        k = 0
        for r in range(h):
            r2 = r + dr
            if di >= 2 and (r2 < 0 or r2 >= h):
                r2 = -1
            for c in range(w):
                i = r * w + c
                b = root[i]
                if b == 0 or not alive[b]:
                    continue
                if r2 >= 0:
                    c2 = c + dc
                    c2 += w if c2 < 0 else 0
                    c2 -= w if c2 >= w else 0
                    if root[r2 * w + c2] == b:
                        continue
                a = _look(nodes, raw, root, cls, use_cls, i, b, dr, dc, h, w, steps, depth)
                if a < 0:
                    continue
                total[b] += 1
                if votes[b] == 0:
                    cand[b] = a
                    votes[b] = 1
                elif cand[b] == a:
                    votes[b] += 1
                else:
                    votes[b] -= 1
                out_b[k] = b
                out_a[k] = a
                k += 1
        votes[:] = 0
        for j in range(k):
            votes[out_b[j]] += out_a[j] == cand[out_b[j]]
        for b in range(1, m):
            if di == 0:
                target[b] = cand[b]
            alive[b] &= (target[b] != 0) & (cand[b] == target[b]) & (2 * votes[b] > total[b])
    for b in range(1, m):
        if alive[b] and parent[b] == b:
            union(parent, b, target[b])


#: (elevation bytes, azimuth offset bytes, width, reach) -> walk_tables_offset; cleared when
#: full
_TABLES: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}


def cached_walk_tables(
    elevation: np.ndarray, width: int, reach: int, azimuth_offset: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`walk_tables_offset`, computed once per elevation, azimuth offsets (None: zeros),
    width and reach."""
    offset = offset_input(azimuth_offset, elevation.size)
    key = (elevation.tobytes(), offset.tobytes(), width, reach)
    out = _TABLES.get(key)
    if out is None:
        if len(_TABLES) >= 64:
            _TABLES.clear()
        out = _TABLES[key] = walk_tables_offset(elevation, offset, width, reach)
    return out


_LEVEL: dict[tuple, np.ndarray] = {}
#: the level rule's tables when it is off (spacing, sin and |tan| of the elevations): not read
_NO_LEVEL = (np.zeros((1, 1)), np.zeros(1), np.zeros(1))
#: the pixels' classes without semantics: not read
_NO_CLASSES = np.zeros(1, dtype=np.int64)


def cached_level_tables(elevation: np.ndarray, reach: int) -> np.ndarray:
    """:func:`level_tables`, computed once per elevation and reach."""
    key = (elevation.tobytes(), reach)
    out = _LEVEL.get(key)
    if out is None:
        if len(_LEVEL) >= 64:
            _LEVEL.clear()
        out = _LEVEL[key] = level_tables(elevation.astype(np.float64), reach)
    return out


@njit(cache=True)
def bridge_pixels(*args) -> np.ndarray:  # noqa: ANN002
    """Labels per pixel of :func:`_bridge_components` (same arguments), (H, W) int32."""
    labels, final = _bridge_components(*args)
    return pixel_output(labels, final).reshape(args[0].shape)


@njit(cache=True)
def bridge_points(point_pixel: np.ndarray, *args) -> np.ndarray:  # noqa: ANN002
    """Labels per point (``point_pixel``: pixel of every point, -1 none) of
    :func:`_bridge_components` (the other arguments)."""
    labels, final = _bridge_components(*args)
    return point_output(labels, final, point_pixel)


def run_bridge(
    ranges: np.ndarray,
    elevation: np.ndarray,
    threshold_m: float,
    gamma_deg: float,
    reach_px: int,
    min_size: int,
    skip: np.ndarray | None = None,
    weights: np.ndarray | None = None,
    point_pixel: np.ndarray | None = None,
    attached: np.ndarray | None = None,
    fixed_side_gaps: bool = False,
    level_tolerance: float = LEVEL_TOLERANCE,
    level_margin: float = LEVEL_MARGIN,
    level_cap_m: float = LEVEL_CAP_M,
    level_support: LevelSupport = LEVEL_SUPPORT_DEFAULT,
    azimuth_offset: np.ndarray | None = None,
    open_holes_px: int | None = OPEN_HOLES_PX,
    seen_through_m: float = 0.0,
    classes: np.ndarray | None = None,
) -> np.ndarray:
    """Bridge labels per pixel, or per point given ``point_pixel`` (see :func:`bridge_labels`;
    ``skip``: pixels left out even with a range, e.g. ground; ``attached``: held pixels, see
    :func:`flic_cli.methods.connections.components`; ``level_tolerance`` > 0 turns the
    level-surface rule on; ``azimuth_offset``: (H,) of every row, radians, None = zeros;
    ``open_holes_px``: the most open holes a sideways walk crosses, None or ``>= reach_px`` = no
    limit; ``seen_through_m``: the deepest a cluster seen through a nearer one lies behind it,
    metres, 0 = off; ``classes``: (H, W) int class of every pixel, with which a cluster is seen
    through a nearer one of its own class only, None = any)."""
    if reach_px < 1:
        raise ValueError(f"reach_px must be >= 1, got {reach_px}")
    if open_holes_px is not None and open_holes_px < 0:
        raise ValueError(f"open_holes_px must be >= 0 or None, got {open_holes_px}")
    if seen_through_m < 0:
        raise ValueError(f"seen_through_m must be >= 0, got {seen_through_m}")
    if level_support not in LEVEL_SUPPORT:
        raise ValueError(f"level_support must be one of {LEVEL_SUPPORT}, got {level_support!r}")
    if classes is not None and np.shape(classes) != np.shape(ranges):
        raise ValueError(f"classes has shape {np.shape(classes)}, the image {np.shape(ranges)}")
    ranges, elevation, skip, use_skip, weights, use_weights = kernel_inputs(
        ranges, elevation, skip, weights
    )
    cos_t, sin_t = cached_walk_tables(elevation, ranges.shape[1], int(reach_px), azimuth_offset)
    level_on = level_tolerance > 0
    if level_on:
        spacing = cached_level_tables(elevation, int(reach_px))
        sin_e, tan_e = np.sin(elevation), np.abs(np.tan(elevation))
    else:  # not read
        spacing, sin_e, tan_e = _NO_LEVEL
    level = LevelRule(
        bool(level_on), sin_e, tan_e, spacing, float(level_tolerance), float(level_margin),
        float(level_cap_m), LEVEL_SUPPORT.index(level_support),
    )  # fmt: skip
    args = (
        ranges, skip, use_skip, cos_t, sin_t, float(threshold_m),
        float(np.sin(np.radians(gamma_deg))), int(reach_px), int(min_size), weights, use_weights,
        attached_input(attached), bool(fixed_side_gaps), level,
        # no limit: the walk without the count (the same graph, as a walk has at most reach_px
        # steps)
        -1 if open_holes_px is None or open_holes_px >= reach_px else int(open_holes_px),
        float(seen_through_m),
        _NO_CLASSES if classes is None else np.ascontiguousarray(classes, np.int64).reshape(-1),
        classes is not None,
    )  # fmt: skip
    if point_pixel is None:
        return bridge_pixels(*args)
    return bridge_points(np.ascontiguousarray(point_pixel, dtype=np.int64), *args)


@dataclass(frozen=True, config=STRICT)
class Bridge:
    """Bridge as a :class:`flic_cli.methods.base.Method` (see :func:`bridge_labels`).

    Attributes
    ----------
    threshold_m : link distance near the sensor, metres.
    gamma_deg : angle that sets the link distance of far measurements, ``d sin(gamma)``, degrees.
    reach_px : longest walk over holes and occluders, pixels.
    min_size : smallest cluster kept, points of the evaluated set (a pixel counts its points).
    fixed_side_gaps : a walk with a sideways step that has passed an open gap links only within
        ``threshold_m`` (module docstring, "Gaps beside"); off by default.
    level_tolerance : the level-surface link of the up walk: how far from where a level surface
        through p would meet q's beam q may lie, a fraction of the footprint spacing; 0 = off
        (module docstring, "Level surfaces").
    level_margin : the level link reaches this many times the footprint spacing of a level
        surface at p's height between the two beams.
    level_cap_m : no level link where the footprint it follows (times the margin) exceeds this,
        metres.
    level_support : what a level link needs besides p and q: ``"beyond"`` the node right above q
        level with q (the level surface goes on beyond q), ``"either"`` that or the node right
        below p level with p, ``"none"`` nothing (module docstring, "Level surfaces").
    open_holes_px : the most open holes (empty pixels without a surface at p's range in their
        column) a sideways walk crosses, pixels; ``>= reach_px`` = no limit (module docstring,
        "Open holes").
    seen_through_m : with semantics (a run with ``--semantics``), a cluster that the scan sees
        through a nearer one of its class (its outline looks onto that cluster above, below, left
        and right) joins it when at most this far behind it, metres; 0 = off (module docstring,
        "Seen through").
    seen_through_agnostic : the same without semantics, whatever the classes (off by default:
        a motorcycle behind a car's windows joins the car; module docstring, "Seen through").
    """

    threshold_m: Annotated[float, Field(gt=0, description="link distance near, metres")] = 0.35
    gamma_deg: Annotated[
        float, Field(ge=0, lt=30, description="far link distance d sin(gamma), degrees")
    ] = 2.0
    reach_px: Annotated[int, Field(ge=1, le=256, description="longest walk, pixels")] = 12
    min_size: Annotated[int, Field(ge=1, description="smallest cluster kept, points")] = 100
    fixed_side_gaps: Annotated[
        bool, Field(description="sideways walks over open gaps link within threshold_m only")
    ] = False
    level_tolerance: Annotated[
        float, Field(ge=0, le=1, description="level link tolerance, footprints (0 = off)")
    ] = LEVEL_TOLERANCE
    level_margin: Annotated[
        float, Field(gt=0, le=10, description="level link: times the footprint spacing")
    ] = LEVEL_MARGIN
    level_cap_m: Annotated[
        float, Field(gt=0, le=20, description="level link: longest reach, metres")
    ] = LEVEL_CAP_M
    level_support: Annotated[
        LevelSupport, Field(description="level link: the third node it needs (beyond q, either)")
    ] = LEVEL_SUPPORT_DEFAULT
    open_holes_px: Annotated[
        int | None, Field(ge=0, description="most open holes a sideways walk crosses (px)")
    ] = OPEN_HOLES_PX
    seen_through_m: Annotated[
        float, Field(ge=0, le=50, description="far side seen through: deepest, metres (0 = off)")
    ] = SEEN_THROUGH_M
    seen_through_agnostic: Annotated[
        bool, Field(description="join clusters seen through nearer ones without semantics too")
    ] = False
    main_param: ClassVar[str] = "threshold_m"
    sweep_range: ClassVar[tuple[float, float, float]] = (0.2, 1.0, 0.05)
    sweep_label: ClassVar[str] = "distance threshold [m]"
    slow: ClassVar[bool] = False
    #: takes the semantic classes in a run with them (``--semantics``), for ``seen_through_m``
    uses_semantics: ClassVar[bool] = True

    def segment(
        self,
        image: RangeImage,
        points: np.ndarray,
        ground: Ground | None,
        semantics: np.ndarray | None = None,
    ) -> np.ndarray:
        """Per-point labels; ``semantics``: (N,) raw SemanticKITTI class of every point, in a
        run with semantics (the seen-through rule then joins clusters of one class only)."""
        left_out, attached = ground_parts(ground)
        classes = None if semantics is None else pixel_classes(image, semantics)
        depth = self.seen_through_m if semantics is not None or self.seen_through_agnostic else 0
        return run_bridge(
            image.ranges,
            image.elevation,
            self.threshold_m,
            self.gamma_deg,
            self.reach_px,
            self.min_size,
            left_out,
            point_weights(image),
            image.point_pixel,
            attached,
            self.fixed_side_gaps,
            self.level_tolerance,
            self.level_margin,
            self.level_cap_m,
            self.level_support,
            image.azimuth_offset,
            self.open_holes_px,
            depth,
            classes,
        )


def pixel_classes(image: RangeImage, semantics: np.ndarray) -> np.ndarray:
    """(H, W) int64 learning class (:func:`flic_cli.classes.learning_class`) of every pixel of
    ``image``: that of its last point (``semantics``: raw class of every point), -1 where no
    point falls."""
    return image.pixel_values(learning_class(np.asarray(semantics)).astype(np.int64), fill=-1)


def bridge_labels(
    ranges: np.ndarray,
    elevation: np.ndarray,
    threshold_m: float = Bridge.threshold_m,
    gamma_deg: float = Bridge.gamma_deg,
    reach_px: int = Bridge.reach_px,
    min_size: int = Bridge.min_size,
    mask: np.ndarray | None = None,
    weights: np.ndarray | None = None,
    fixed_side_gaps: bool = Bridge.fixed_side_gaps,
    level_tolerance: float = Bridge.level_tolerance,
    level_margin: float = Bridge.level_margin,
    level_cap_m: float = Bridge.level_cap_m,
    level_support: LevelSupport = Bridge.level_support,
    azimuth_offset: np.ndarray | None = None,
    open_holes_px: int | None = Bridge.open_holes_px,
    seen_through_m: float = 0.0,
    classes: np.ndarray | None = None,
) -> np.ndarray:
    """Bridge cluster labels of a range image (the graph is defined in the module docstring).

    Parameters
    ----------
    ranges : (H, W) ranges, metres, 0 = no measurement.
    elevation : (H,) row elevations, radians.
    threshold_m : link distance near the sensor, metres.
    gamma_deg : beyond ``threshold_m / sin(gamma)`` the link distance is ``d sin(gamma)``,
        degrees (0 = fixed threshold).
    reach_px : longest walk, pixels (rows or columns).
    min_size : smallest cluster, points (the sum of its pixels' ``weights``).
    mask : (H, W) bool, pixels to cluster (default: all valid pixels).
    weights : (H, W) int, points per pixel (default 1 per pixel).
    fixed_side_gaps : sideways walks over open gaps link within ``threshold_m`` only (module
        docstring, "Gaps beside").
    level_tolerance, level_margin, level_cap_m : the level-surface link of the up walk (module
        docstring, "Level surfaces"; ``level_tolerance`` 0 = off), -, -, metres.
    level_support : what a level link needs besides p and q: ``"beyond"``, ``"either"``,
        ``"none"`` (:class:`Bridge`).
    azimuth_offset : (H,) azimuth offset of every row, radians (a pixel's azimuth is its
        column's centre plus it; :attr:`flic_cli.range_image.RangeImage.azimuth_offset`);
        None = zeros.
    open_holes_px : the most open holes a sideways walk crosses (module docstring, "Open
        holes"), pixels; None or ``>= reach_px`` = no limit.
    seen_through_m : the deepest a cluster seen through a nearer one lies behind it and still
        joins it (module docstring, "Seen through"), metres; 0 = off.
    classes : (H, W) int class of every pixel: a cluster joins a nearer one it is seen through
        only where the pixels it looks from and onto are of one class; None = any class.

    Returns
    -------
    (H, W) int32, 0 = unclustered, 1..K clusters numbered in raster order.
    """
    skip = None if mask is None else ~np.asarray(mask, dtype=bool)
    return run_bridge(
        ranges, elevation, threshold_m, gamma_deg, reach_px, min_size, skip, weights, None, None,
        fixed_side_gaps, level_tolerance, level_margin, level_cap_m, level_support,
        azimuth_offset, open_holes_px, seen_through_m, classes,
    )  # fmt: skip
