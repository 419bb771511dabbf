"""Method parameters that follow a sensor's beam table (docs/sensors.md: methods on other sensors).

Every run derives them once per dataset, when it builds its components (:func:`for_dataset`):
from the first selected frame's range image, whose rows are the sensor model's beams (Ouster,
Velodyne, PCD, nuScenes, bags: ``flic info`` prints them) or the rows recovered from a
SemanticKITTI scan (their elevations estimated from the points) or a Moosmann log's. A value a
config file sets (:attr:`flic_cli.config.schema.MethodSpec.given`) wins over a derived one.

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

import dataclasses
import functools
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit

if TYPE_CHECKING:
    from flic_cli.config.schema import Config
    from flic_cli.range_image import RangeImage

__all__ = [
    "BRIDGE_GAPS_PER_GAMMA",
    "BRIDGE_SWITCH_M",
    "RUN_GROUND_RANGE_M",
    "RUN_JUMP_FLOOR",
    "RUN_JUMP_MARGIN",
    "STREET_ELEVATION_DEG",
    "BeamTable",
    "beams_of_dataset",
    "bridge_parameters",
    "column_run_jumps",
    "derived_lines",
    "derived_parameters",
    "for_beams",
    "for_dataset",
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


#: The column remover's run limit where the beams are close (the value its sweep chose on the
#: HDL-64E, ``results/ground/``): a share of ``rho``.
RUN_JUMP_FLOOR = 0.3
#: What the run allows beyond the ground's own growth between two beams: a share of ``rho``. On
#: the HDL-64E the ground's range grows by at most 19 % from a beam to the next one up within
#: :data:`RUN_GROUND_RANGE_M` (the sample's table), so that its 0.3 leaves at least 0.11 there.
RUN_JUMP_MARGIN = 0.1
#: Rows whose ground return (on level ground) lies beyond this range keep the floor, metres:
#: there the street's ground returns are sparse (the sample keeps 5 % of them at 27 m), and near
#: the horizon the growth from one beam to the next is unbounded.
RUN_GROUND_RANGE_M = 40.0


@functools.lru_cache(maxsize=32)
def _run_jumps(elevation: bytes, sensor_height_m: float) -> np.ndarray:
    """:func:`column_run_jumps` of a table given as its float64 bytes, cached: a sensor's own
    table repeats every frame; the rows recovered from a SemanticKITTI scan differ per frame
    (their elevations are estimated from its points), so there every frame computes it."""
    el = np.frombuffer(elevation, dtype=np.float64)
    # numpy's tan (not numba's libm one, which differs in the last bit on some inputs)
    out = _run_jump_rows(
        el, np.tan(-el), sensor_height_m, RUN_JUMP_FLOOR, RUN_JUMP_MARGIN, RUN_GROUND_RANGE_M
    )
    out.setflags(write=False)
    return out


@njit(cache=True)
def _run_jump_rows(
    el: np.ndarray,
    tan_down: np.ndarray,
    sensor_height_m: float,
    floor: float,
    margin: float,
    ground_range_m: float,
) -> np.ndarray:
    """(H,) float64 limits: ``floor`` on every row, but where the row above sees level ground
    within ``ground_range_m`` (metres) the ground's growth to it plus ``margin``, at least
    ``floor`` (shares of ``rho``); ``el`` the rows' elevations and ``tan_down`` their
    ``tan(-el)`` (radians), ``sensor_height_m`` metres. Each value is the same float64
    operations on the same operands as the whole-array form of the rule
    (``tests/test_sensor_params.py`` checks it bit for bit): one loop instead of a dozen numpy
    calls on (H,) arrays, every frame on SemanticKITTI, whose rows' elevations the cache never
    finds twice."""
    out = np.full(el.size, floor)
    for r in range(1, el.size):
        upper = el[r - 1]  # the row above (row 0 = top)
        if upper < 0.0 and el[r] < upper:  # tan_down[r - 1] > 0: no division by zero
            reach = sensor_height_m / tan_down[r - 1]  # level ground under the row above, metres
            if reach <= ground_range_m:
                growth = tan_down[r] / tan_down[r - 1] - 1.0
                out[r] = max(floor, growth + margin)
    return out


def column_run_jumps(elevation: np.ndarray, sensor_height_m: float = 1.73) -> np.ndarray:
    """The column ground remover's depth-jump limit above every row, from the beam table.

    A step or a seed of :class:`flic_cli.ground.column.ColumnGround` is confirmed by the valid
    cells above it, and a cell farther than ``(1 + jump) rho`` of the one below ends that run
    (a depth jump: the background behind an object). Level ground seen by a beam at elevation
    ``e`` lies at ``rho = h / tan(-e)``, so from a row to the next beam up the ground's own range
    grows by ``tan(-e_r) / tan(-e_{r-1}) - 1``: 2-19 % on the HDL-64E within 40 m, but 67 %
    from the VLP-32C's -25 deg beam to its -15.6 deg one (3.7 to 6.2 m) and 40 % from there to
    -11.3 deg, where the fixed 0.3 ended every run on the ground and its two lowest rows lost
    all their ground (``results/sensors-synthetic/ground-column/``). So the limit above row
    ``r`` is ``max(RUN_JUMP_FLOOR, growth + RUN_JUMP_MARGIN)`` where the row above sees level
    ground within :data:`RUN_GROUND_RANGE_M`, and :data:`RUN_JUMP_FLOOR` elsewhere. It is read
    for the pair of the run's previous cell's row and the next row up (a run that skips empty
    rows keeps that row's limit, as the fixed 0.3 did).

    Parameters
    ----------
    elevation : (H,) row elevations, radians, positive up, row 0 = the top row (image order).
    sensor_height_m : the sensor above the road, metres.

    Returns
    -------
    (H,) float64 read-only limits, a share of ``rho`` (row 0's is never read: nothing above).
    """
    table = np.ascontiguousarray(elevation, dtype=np.float64).tobytes()
    return _run_jumps(table, float(sensor_height_m))


@dataclass(frozen=True, eq=False)
class BeamTable:
    """What the derived parameters read of a sensor.

    Attributes
    ----------
    elevation : (H,) beam (row) elevations, radians, positive up, row 0 = top.
    columns : columns per revolution (the range image's width).
    source : where the table came from, in a few words (for ``flic info`` and notes).
    """

    elevation: np.ndarray
    columns: int
    source: str = "range image"

    @classmethod
    def of_image(cls, image: RangeImage, source: str = "range image") -> BeamTable:
        """The rows and columns of a range image."""
        return cls(np.asarray(image.elevation, dtype=np.float64), int(image.shape[1]), source)


def derived_parameters(method: Any, beams: BeamTable) -> dict[str, Any]:
    """The parameters of ``method`` (a built component) that follow the beam table, with their
    derived values; empty when none differs from the component's defaults.

    Only Bridge has such parameters (:func:`bridge_parameters`); the column ground remover
    derives its per-row run limits from the image itself (:func:`column_run_jumps`). What stays
    fixed and why: docs/sensors.md, "Methods on other sensors".
    """
    from flic_cli.methods.bridge import Bridge

    if isinstance(method, Bridge):
        try:
            return bridge_parameters(beams.elevation)
        except ValueError:  # a table without two street beams: keep the defaults
            return {}
    return {}


def for_beams(config: Config, beams: BeamTable) -> tuple[Config, dict[str, dict[str, Any]]]:
    """``config`` with every variant's sensor-dependent parameters derived from ``beams``; and
    the derived values per variant (only those applied). The parameters one rule derives
    together (Bridge's ``gamma_deg`` and ``threshold_m``) are left at the config's values when
    its file sets any of them.
    """
    methods = dict(config.methods)
    applied: dict[str, dict[str, Any]] = {}
    for name, spec in config.methods.items():
        values = derived_parameters(spec.method, beams)
        if values and not spec.given.isdisjoint(values):
            continue  # the config sets one of them: the others follow it, not the sensor
        if values:
            method = dataclasses.replace(spec.method, **values)
            methods[name] = dataclasses.replace(spec, method=method)
            applied[name] = values
    if not applied:
        return config, applied
    return dataclasses.replace(config, methods=methods), applied


def beams_of_dataset(ds: Any, refs: list, projection: Any) -> BeamTable | None:
    """The beam table of a dataset: the first of ``refs``'s range image (a sensor reader's own
    image, rows = its sensor model's beams; else the config's ``projection`` of its points).
    None when there is no frame or it cannot be read (the run then reports the bad frame
    itself)."""
    from flic_cli.errors import FlicInputError

    if not refs:
        return None
    try:
        with warnings.catch_warnings():  # the run reads the frame again and warns then
            warnings.simplefilter("ignore")
            frame = ds.load(refs[0])
            image = frame.image if frame.image is not None else projection(frame.points)
    except FlicInputError:
        return None
    if frame.image is not None:
        model = ds.sensor(refs[0]) if hasattr(ds, "sensor") else None
        how = getattr(model, "angles_from", None)
        source = f"sensor model ({how})" if how else "the reader's range image"
        return BeamTable.of_image(image, source)
    return BeamTable.of_image(image, f"{image.projection} projection of the first frame")


def for_dataset(config: Config, ds: Any, refs: list) -> Config:
    """``config`` with the parameters derived from the dataset's sensor (:func:`for_beams` on
    :func:`beams_of_dataset`), once per run; the runs store the values used in their
    ``run.json`` (evaluate, sweep) and ``flic info`` prints them. A folder of recordings from
    different sensors takes the first selected one's (run them one by one otherwise)."""
    beams = beams_of_dataset(ds, refs, config.projection)
    return config if beams is None else for_beams(config, beams)[0]


def derived_lines(beams: BeamTable, config: Config) -> list[str]:
    """What a run derives from ``beams`` with ``config`` (e.g. the shipped presets,
    ``flic_cli.config.load_config()``), as ``flic info`` prints it: Bridge's link distances and
    column's run limits."""
    applied = for_beams(config, beams)[1]
    bridge = {tuple(sorted(v.items())) for k, v in applied.items()}
    text = "; ".join(", ".join(f"{k} = {v:g}" for k, v in b) for b in sorted(bridge))
    lines = [f"derived for Bridge: {text}" if text else "derived for Bridge: its defaults"]
    jumps = column_run_jumps(beams.elevation)
    raised = int(np.count_nonzero(jumps > RUN_JUMP_FLOOR))
    lines.append(
        f"derived for column: run limit above {raised} row(s) raised to at most {jumps.max():.3g}"
        if raised
        else f"derived for column: run limit {RUN_JUMP_FLOOR:g} on every row"
    )
    return lines
