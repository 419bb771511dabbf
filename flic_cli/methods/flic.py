"""FLIC: Euclidean clustering on the range image with Map Connections (paper section III-B)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from flic_cli.methods._unionfind import DISTANCE, connect_labels
from flic_cli.range_image import RangeImage

MC_MODES = ("map", "neighbour")


def connection_sets(
    maps: tuple[tuple[int, int], ...] | list, mc_mode: str = "map"
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The connection sets of the kernel: direct neighbours first, then one per Map Connection.

    Parameters
    ----------
    maps : steps ``(rows, cols)`` or ``(rows, cols, row_offset, col_offset)`` of each MC.
    mc_mode : ``"map"``: an MC is the sub-image of every step-th row and column (from the offset),
        clustered with the same distance test at the angle of that step and merged into the direct
        clusters. ``"neighbour"``: every measurement is connected to its step-th neighbour below
        and to the right (the union of the map reading over all offsets).

    Returns
    -------
    steps (M, 2), offsets (M, 2), lattice (M,) arrays for :func:`connect_labels`.
    """
    if mc_mode not in MC_MODES:
        raise ValueError(f"mc_mode must be one of {MC_MODES}, got {mc_mode!r}")
    steps = [(1, 1)]
    offsets = [(0, 0)]
    for m in maps:
        m = tuple(int(v) for v in m)
        if len(m) not in (2, 4) or m[0] < 1 or m[1] < 1:
            raise ValueError(f"a map is (row_step, col_step[, row_offset, col_offset]), got {m}")
        steps.append(m[:2])
        offsets.append(m[2:] if len(m) == 4 else (0, 0))
    lattice = [True] + [mc_mode == "map"] * len(maps)
    return (
        np.array(steps, dtype=np.int64),
        np.array(offsets, dtype=np.int64),
        np.array(lattice, dtype=np.bool_),
    )


def flic_labels(
    ranges: np.ndarray,
    elevation: np.ndarray,
    threshold_m: float = 0.8,
    min_size: int = 100,
    maps: tuple = (),
    mc_mode: str = "map",
    mask: np.ndarray | None = None,
) -> np.ndarray:
    """FLIC cluster labels of a range image.

    Two measurements ``d1, d2`` separated by the angle ``alpha`` are connected when
    ``d1^2 + d2^2 - 2 cos(alpha) d1 d2 < threshold_m^2`` (the law of cosines: their 3D distance is
    below the threshold). Direct connections are the 4-neighbours with horizontal wrap-around; each
    Map Connection adds the connections of its step (see :func:`connection_sets`). Clusters are the
    connected components; those with fewer than ``min_size`` measurements are dropped.

    Parameters
    ----------
    ranges : (H, W) float32 ranges, metres, 0 = no measurement.
    elevation : (H,) row elevations, radians.
    threshold_m : distance threshold t, metres.
    min_size : smallest cluster, in measurements (pixels).
    maps : Map Connection steps, see :func:`connection_sets`.
    mc_mode : ``"map"`` or ``"neighbour"``.
    mask : (H, W) bool, pixels to cluster (default: all valid pixels).

    Returns
    -------
    (H, W) int32, 0 = unclustered, 1..K clusters.
    """
    ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    if mask is None:
        mask = ranges > 0
    steps, offsets, lattice = connection_sets(maps, mc_mode)
    return connect_labels(
        ranges,
        np.ascontiguousarray(mask),
        np.asarray(elevation, dtype=np.float64),
        steps,
        offsets,
        lattice,
        DISTANCE,
        float(threshold_m) ** 2,
        int(min_size),
    )


@dataclass(frozen=True)
class Flic:
    """FLIC as a :class:`flic_cli.methods.base.Method` (see :func:`flic_labels`)."""

    threshold_m: float = 0.8
    min_size: int = 100
    maps: tuple = ()
    mc_mode: str = "map"
    main_param: ClassVar[str] = "threshold_m"

    def __post_init__(self) -> None:
        connection_sets(self.maps, self.mc_mode)  # validate early

    def segment(
        self, image: RangeImage, points: np.ndarray, ground: np.ndarray | None
    ) -> np.ndarray:
        mask = image.ranges > 0 if ground is None else (image.ranges > 0) & ~ground
        labels = flic_labels(
            image.ranges,
            image.elevation,
            self.threshold_m,
            self.min_size,
            self.maps,
            self.mc_mode,
            mask,
        )
        return image.point_labels(labels)
