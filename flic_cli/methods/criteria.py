"""Edge criteria of the range-image graphs: when two neighbouring measurements are connected.

Each test is written once, as an ``inline="always"`` numba function, and used by the scalar code
(the 360 deg seam, the Map Connections' flagged pairs) and by the row loops that LLVM vectorises
(:mod:`flic_cli.methods.connections`, :mod:`flic_cli.methods.bridge`), as depth_clustering keeps
its ``diff_helpers`` apart from its image labelers. The tests are branch-free, so that a loop
over a row that calls one stays vector code. Their operations and their order are the ones the
labels were defined with (float32 squares of the ranges, float64 cross term), so that no edge
changes.

Two measurements at ranges ``d1``, ``d2`` (metres, > 0) whose rays are the angle ``alpha``
apart (cos ``c``, sin ``s``):

- :data:`DISTANCE` (FLIC, Bridge): connected when their 3D distance is below the threshold,
  ``d1^2 + d2^2 - 2 cos(alpha) d1 d2 < t^2`` (the law of cosines; ``param`` = t^2, m^2);
- :data:`ANGLE` (Bogoslavskyi & Stachniss): connected when the angle
  ``beta = atan2(d_min sin(alpha), d_max - d_min cos(alpha))`` exceeds theta, tested without
  arctan: ``d_min sin(alpha) > tan(theta) (d_max - d_min cos(alpha))`` or the bracket is not
  positive (beta >= 90 deg) (``param`` = tan(theta)).

The angle ``alpha`` itself is :func:`ray_angle`: the angle between the rays of the two pixels,
each at its row's elevation and its own azimuth (the column's centre plus the row's azimuth
offset, :attr:`flic_cli.range_image.RangeImage.azimuth_offset`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

DISTANCE = 0  # connected when d1^2 + d2^2 - 2 cos(a) d1 d2 < param   (param = t^2)
ANGLE = 1  # connected when atan2(d_min sin a, d_max - d_min cos a) > theta  (param = tan theta)


@njit(cache=True)
def ray_angle(el1: float, el2: float, az1: float, az2: float) -> float:
    """The angle between two rays at elevations ``el1``, ``el2`` and azimuths ``az1``, ``az2``
    (radians): ``el1 - el2`` (signed) when the azimuths are equal, as for two pixels of one column
    without azimuth offsets (exactly the value the labels were defined with), else the great-circle
    angle by the haversine formula, ``hav(alpha) = hav(el1 - el2) + cos(el1) cos(el2)
    hav(az1 - az2)`` (>= 0)."""
    a = el1 - el2
    if az1 == az2:
        return a
    h = np.sin(0.5 * a) ** 2 + np.cos(el1) * np.cos(el2) * np.sin(0.5 * (az1 - az2)) ** 2
    return 2.0 * np.arcsin(min(1.0, np.sqrt(h)))


@njit(cache=True, inline="always")
def distance_edge(d1, d2, c: float, param: float) -> bool:  # noqa: ANN001
    """:data:`DISTANCE`: the 3D distance of ``d1`` and ``d2`` at the angle of cosine ``c`` is
    below ``sqrt(param)``."""
    return d1 * d1 + d2 * d2 - 2.0 * c * d1 * d2 < param


@njit(cache=True, inline="always")
def angle_edge(d1, d2, c: float, s: float, param: float) -> bool:  # noqa: ANN001
    """:data:`ANGLE`: the angle beta of ``d1`` and ``d2`` at the angle (cos ``c``, sin ``s``)
    exceeds ``arctan(param)``."""
    big = d1 if d1 > d2 else d2
    small = d2 if d1 > d2 else d1
    den = big - small * c
    return (den <= 0.0) | (small * s > param * den)


@njit(cache=True, inline="always")
def edge(d1, d2, c: float, s: float, criterion: int, param: float) -> bool:  # noqa: ANN001
    """Whether two measurements ``d1``, ``d2`` (> 0) at the angle (cos ``c``, sin ``s``) are
    connected by ``criterion`` (:data:`DISTANCE` or :data:`ANGLE`) with ``param``."""
    if criterion == DISTANCE:
        return distance_edge(d1, d2, c, param)
    return angle_edge(d1, d2, c, s, param)
