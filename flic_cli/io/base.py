"""The one small interface every dataset format implements."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar, Protocol, TypeVar

import numpy as np

from flic_cli.errors import FlicInputError

if TYPE_CHECKING:
    from flic_cli.range_image import RangeImage

T = TypeVar("T")


@dataclass(frozen=True)
class FrameRef:
    """A cheap, picklable reference to one frame of a dataset (sent to worker processes).

    Attributes
    ----------
    sequence : sequence name (SemanticKITTI ``"00"``; Moosmann: the log folder's name; a
        recording: the file's name)
    frame : frame number (``000123.bin`` -> 123, ``scan00123.png`` -> 123; in a multi-frame file,
        its frame number as the format counts them)
    path : the file that holds the frame (``.bin``, ``.png``; a pcap or a bag holds many)
    label_path : the file holding the frame's ground truth (``path`` itself for a format that
        stores labels with the points), or None when the format or the frame has none
    format : the format's name in :data:`flic_cli.registry.FORMATS`
    index : position of the frame inside ``path`` (0-based) when the file holds many frames
        (the format's entry says ``frames_per_file="many"``); 0 for a file per frame
    """

    sequence: str
    frame: int
    path: Path
    label_path: Path | None
    format: str
    index: int = 0


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
    stored_labels : (N_read,) uint32 labels of every point as stored, the dropped ones too; set
        by the format when it dropped points (``finite`` is not None) and the frame has labels.
    """

    ref: FrameRef
    points: np.ndarray
    labels: np.ndarray | None
    image: RangeImage | None = None
    finite: np.ndarray | None = None
    stored_labels: np.ndarray | None = None

    @property
    def n_read(self) -> int:
        """Number of points as stored in the file (outputs hold one value per such point)."""
        return self.points.shape[0] if self.finite is None else int(self.finite.shape[0])

    def labels_as_stored(self) -> np.ndarray | None:
        """(N_read,) labels of every point as stored (dropped points too); None without labels.

        Raises
        ------
        ValueError
            When the format dropped points but did not keep their labels (a bug of the format).
        """
        if self.labels is None or self.finite is None:
            return self.labels
        if self.stored_labels is None:
            raise ValueError(f"{self.ref.path}: the format kept no labels of its dropped points")
        return self.stored_labels


class Dataset(Protocol):
    """A dataset format: lists its frames, loads one frame. Workers read frames only through
    :meth:`load`, and decide what a run may do only from the capabilities declared here.

    A format class also recognises its data (``detect(path) -> bool``, a static method that must
    not need the format's optional package), is constructed as
    ``cls(root, sequences, frames, require_labels)``, may define ``check_installed()`` (a static
    method raising :class:`flic_cli.errors.FlicInputError` with an install hint) and is named in
    :data:`flic_cli.registry.FORMATS`, whose entry declares whether it can be labelled, how many
    frames a file holds and its optional package.

    Attributes
    ----------
    root : the data it was opened on.
    format : its name in :data:`flic_cli.registry.FORMATS`.
    point_semantics : whether its predictions can carry a semantic class per point
        (``flic segment --semantics``; SemanticKITTI's ``.label`` lower 16 bits).
    """

    root: Path
    format: str
    point_semantics: ClassVar[bool]

    def labelled(self) -> bool:
        """Whether some selected frame has ground-truth labels (:class:`Frame` ``labels``)."""
        ...

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
