"""The sensor model of a recording: its beams, their angles, and where those came from.

Every sensor reader (:mod:`flic_cli.io.ouster`, :mod:`flic_cli.io.velodyne`,
:mod:`flic_cli.io.pcd`, :mod:`flic_cli.io.nuscenes`) describes its recording with a
:class:`SensorModel`; ``flic info`` prints it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: Where a sensor model's beam angles came from (:attr:`SensorModel.angles_from`).
ANGLE_SOURCES = {
    "metadata": "the sensor's metadata (calibration) file",
    "decoder": "the decoder's built-in calibration for the model",
    "fields": "per-point ring / azimuth fields of the file",
    "estimated": "estimated from the points (median elevation per ring)",
}


@dataclass(frozen=True, eq=False)
class SensorModel:
    """The geometry of a spinning lidar as a range image sees it.

    Attributes
    ----------
    name : the sensor, e.g. ``"Ouster OS-2-128"`` or ``"Velodyne VLP-16"``.
    elevation : (H,) float64 elevation of every beam in radians, positive up, row 0 = top beam.
    azimuth_offset : (H,) float64 azimuth of every beam relative to its image column's nominal
        azimuth, in radians (positive = counter-clockwise seen from above); zeros where the
        source gives none.
    columns : columns per revolution (W).
    angles_from : a key of :data:`ANGLE_SOURCES`.
    beam_origin_mm : distance from the lidar origin to the beams' origin in mm (Ouster's
        ``lidar_origin_to_beam_origin_mm``), or None where the source gives none.
    columns_from : where ``columns`` came from, in a few words.
    notes : further facts for ``flic info`` (e.g. which metadata fields were defaulted).
    """

    name: str
    elevation: np.ndarray
    azimuth_offset: np.ndarray
    columns: int
    angles_from: str
    beam_origin_mm: float | None = None
    columns_from: str = "metadata"
    notes: tuple[str, ...] = field(default=())

    @property
    def beams(self) -> int:
        """Number of beams (rows of the range image, H)."""
        return int(self.elevation.size)

    def describe(self) -> dict[str, str]:
        """The model as ``name: text`` lines for ``flic info``."""
        el = np.degrees(self.elevation)
        az = np.degrees(self.azimuth_offset)
        out = {
            "sensor": self.name,
            "beams x columns": f"{self.beams} x {self.columns} (columns from {self.columns_from})",
            "elevation": f"{el.min():+.2f} .. {el.max():+.2f} deg",
            "beam azimuth offsets": f"{az.min():+.2f} .. {az.max():+.2f} deg",
            "beam angles from": f"{self.angles_from} ({ANGLE_SOURCES[self.angles_from]})",
        }
        if self.beam_origin_mm is not None:
            out["beam origin offset"] = f"{self.beam_origin_mm:.3f} mm"
        for i, note in enumerate(self.notes):
            out[f"note {i + 1}"] = note
        return out
