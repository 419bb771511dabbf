"""Method parameters that follow a sensor's beam table (docs/sensors.md: methods on other sensors).

Most parameters of the clusterers are metric (FLIC's 0.8 m, DBSCAN's eps, the minimum sizes) or
scale-free angles (Bogoslavskyi's 10 deg) and stay what they are on every sensor. One is relative
to the beam spacing: Bridge's far link distance ``d sin(gamma_deg)``, chosen on the HDL-64E (beams
0.33-0.52 deg apart, where it spans 4-6 beam gaps). :func:`bridge_parameters` gives Bridge's
parameters for another beam table where the defaults cannot link adjacent beams.

The functions take the beams' elevations in radians (positive up, any order): a
:class:`~flic_cli.range_image.RangeImage`'s ``elevation``, a reader's sensor model, or a sample
profile's ``-radians(pitch_deg)``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "BRIDGE_GAPS_PER_GAMMA",
    "BRIDGE_SWITCH_M",
    "STREET_ELEVATION_DEG",
    "bridge_parameters",
    "street_beam_gap_deg",
]

#: Bridge's far angle ``gamma`` is at least this many beam gaps (see :func:`bridge_parameters`).
BRIDGE_GAPS_PER_GAMMA = 1.5
#: Bridge's near distance ``threshold_m`` is the far one at this range, metres (as the defaults
#: are: 0.35 m = 10 m sin 2 deg).
BRIDGE_SWITCH_M = 10.0
#: Beams at or below this elevation (degrees) see a street's objects from a car's roof; their
#: median gap is the sensor's beam gap.
STREET_ELEVATION_DEG = 3.0


def street_beam_gap_deg(elevation: np.ndarray) -> float:
    """Median elevation gap between adjacent beams at or below :data:`STREET_ELEVATION_DEG`.

    Parameters
    ----------
    elevation : (H,) beam elevations, radians, positive up, any order (at least 2 beams at or
        below :data:`STREET_ELEVATION_DEG`).

    Returns
    -------
    The gap in degrees.
    """
    el = np.sort(np.degrees(np.asarray(elevation, dtype=np.float64)))  # lowest first
    gaps = np.diff(el)[el[:-1] <= STREET_ELEVATION_DEG]
    if gaps.size == 0:
        raise ValueError(f"fewer than two beams at or below {STREET_ELEVATION_DEG} deg")
    return float(np.median(gaps))


def bridge_parameters(elevation: np.ndarray) -> dict[str, float]:
    """Bridge's link distances for a beam table, where its defaults cannot link adjacent beams.

    Bridge links two measurements closer than ``max(threshold_m, d sin(gamma_deg))``. Two beams
    ``g`` apart hit a surface facing the sensor at range ``d`` about ``2 d sin(g / 2)`` apart: on a
    VLP-16 (g = 2 deg) the defaults' ``d sin 2 deg`` is exactly one gap, so that no object beyond
    10 m keeps two rows together (``results/sensors-synthetic/vertical_links.csv``). So
    ``gamma_deg`` becomes at least :data:`BRIDGE_GAPS_PER_GAMMA` times the sensor's beam gap
    (:func:`street_beam_gap_deg`), and ``threshold_m`` the far link distance at
    :data:`BRIDGE_SWITCH_M`, as the defaults are. Beams at most 1.33 deg apart keep the defaults.

    Parameters
    ----------
    elevation : (H,) beam elevations, radians, positive up, any order.

    Returns
    -------
    ``{"gamma_deg": ..., "threshold_m": ...}`` (degrees, metres) where they differ from Bridge's
    defaults; empty where the defaults hold.
    """
    from flic_cli.methods.bridge import Bridge

    gap = street_beam_gap_deg(elevation)
    gamma = round(max(Bridge.gamma_deg, BRIDGE_GAPS_PER_GAMMA * gap), 2)
    if gamma <= Bridge.gamma_deg:
        return {}
    far = BRIDGE_SWITCH_M * float(np.sin(np.radians(gamma)))
    return {"gamma_deg": gamma, "threshold_m": round(max(Bridge.threshold_m, far), 2)}
