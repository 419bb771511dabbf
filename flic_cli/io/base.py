"""The one small interface every dataset format implements."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol, TypeVar

import numpy as np

from flic_cli.errors import FlicInputError
from flic_cli.range_image import RangeImage

T = TypeVar("T")


@dataclass(frozen=True)
class FrameRef:
    """A cheap, picklable reference to one frame of a dataset (sent to worker processes).

    Attributes
    ----------
    sequence : sequence name (SemanticKITTI ``"00"``; Moosmann: the log folder's name)
    frame : frame number (``000123.bin`` -> 123, ``scan00123.png`` -> 123)
    path : the scan file (``.bin`` or ``.png``)
    label_path : the ``.label`` file, or None when the format or the frame has none
    format : ``"semantickitti"`` or ``"moosmann"``
    """

    sequence: str
    frame: int
    path: Path
    label_path: Path | None
    format: str


@dataclass
class Frame:
    """One loaded frame.

    Attributes
    ----------
    ref : where it came from
    points : (N, 3) float32, metres, sensor frame (x forward, y left, z up), in scan order
    labels : (N,) uint32 SemanticKITTI encoding (semantic = low 16 bits, instance = high 16 bits)
        or None when the dataset has no labels
    image : the sensor's own range image when the format is one (Moosmann), else None (the
        points are projected by :func:`flic_cli.projection.project_points`). When set,
        ``points[i]`` is the point of pixel ``image.point_pixel[i]``.
    finite : (N_read,) bool over the points as stored, True for those in ``points`` (points with
        NaN or infinite coordinates are dropped when read); None when all were kept.
    """

    ref: FrameRef
    points: np.ndarray
    labels: np.ndarray | None
    image: RangeImage | None = None
    finite: np.ndarray | None = None

    @property
    def n_read(self) -> int:
        """Number of points as stored in the file (outputs hold one value per such point)."""
        return self.points.shape[0] if self.finite is None else int(self.finite.shape[0])


class Dataset(Protocol):
    """A dataset format: lists its frames, loads one frame.

    A format class also recognises its folders (``detect(path) -> bool``, a static method), is
    constructed as ``cls(root, sequences, frames, require_labels)`` and is named in
    :data:`flic_cli.registry.FORMATS`.
    """

    root: Path
    format: str

    def refs(self) -> list[FrameRef]:
        """Every selected frame, ordered by sequence then frame number."""
        ...

    def folders(self) -> list[Path]:
        """The folders the selected frames live in (outputs must not go inside them)."""
        ...

    def write_prediction(
        self,
        out: Path,
        ref: FrameRef,
        labels: np.ndarray,
        image: RangeImage | None = None,
        semantics: np.ndarray | None = None,
    ) -> Path:
        """Write one frame's cluster ids (one per point as stored) in the format's own way."""
        ...

    def export_path(self, out: Path, ref: FrameRef, suffix: str) -> Path:
        """Where a per-frame export (e.g. ``.ply``) of frame ``ref`` goes under ``out``."""
        ...

    def load(self, ref: FrameRef) -> Frame:
        """Read one frame; raises :class:`flic_cli.errors.FlicInputError` on bad input."""
        ...


def in_frames(frame: int, frames: tuple[int | None, int | None] | None) -> bool:
    """True when ``frame`` lies in ``frames = (start, stop)`` (stop exclusive, None = open)."""
    if frames is None:
        return True
    start, stop = frames
    return (start is None or frame >= start) and (stop is None or frame < stop)


def frames_text(frames: tuple[int | None, int | None]) -> str:
    """``(10, None)`` -> ``"10:"``: a frame range as the command line writes it."""
    start, stop = frames
    return f"{'' if start is None else start}:{'' if stop is None else stop}"


def select_sequences(root: Path, found: dict[str, T], sequences: list[str] | None) -> dict[str, T]:
    """The requested entries of ``found`` (sequence name -> anything), sorted; all when None.

    Raises
    ------
    FlicInputError
        Naming the requested sequences that ``root`` does not have.
    """
    if sequences is None:
        return found
    unknown = [s for s in sequences if s not in found]
    if unknown:
        raise FlicInputError(
            root, f"no sequence {', '.join(unknown)} (found: {', '.join(found) or 'none'})"
        )
    return {s: found[s] for s in sorted(set(sequences))}
