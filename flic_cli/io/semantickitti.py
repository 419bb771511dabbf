"""SemanticKITTI: scans (``.bin``), labels (``.label``), calibration, poses, predictions.

Layout (docs/specification.md): ``<root>/sequences/<NN>/velodyne/<XXXXXX>.bin`` and
``<root>/sequences/<NN>/labels/<XXXXXX>.label``; ``<root>`` may also be one sequence folder.
Predictions use the ``.label`` encoding with the cluster id in the upper 16 bits and the semantic
class (0 = unlabeled unless semantics are given) in the lower 16 bits, in
``<out>/sequences/<NN>/predictions/<XXXXXX>.label``.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numba import njit

from flic_cli.errors import FlicInputError
from flic_cli.io.atomic import atomic_write_bytes, open_regular, read_text
from flic_cli.io.base import Frame, FrameRef, frames_text, in_frames, select_sequences
from flic_cli.labels import encode, instance, semantic
from flic_cli.range_image import RangeImage
from flic_cli.semantics import combine, known_classes

FORMAT = "semantickitti"


class Scan(NamedTuple):
    """One validated scan.

    Attributes
    ----------
    points : (N, 3) float32, metres, sensor frame, scan order; only points with finite coordinates
    remission : (N,) float32, 0..1
    labels : (N,) uint32 SemanticKITTI encoding, or None when no label file was given
    finite : (N_read,) bool over the points as stored in the file, True for those kept in
        ``points``; None when every point was finite (then N_read = N)
    """

    points: np.ndarray
    remission: np.ndarray
    labels: np.ndarray | None
    finite: np.ndarray | None = None


# ---------------------------------------------------------------------------------------------
# Scans and labels
# ---------------------------------------------------------------------------------------------


def _read_array(path: str | Path, dtype: str, record: int, what: str) -> np.ndarray:
    """The content of a binary file as a 1-D array of ``dtype``, read straight into it.

    Parameters
    ----------
    path : the file.
    dtype : little-endian element type (``"<f4"``, ``"<u4"``).
    record : bytes per record; the file size must be a multiple of it.
    what : the record layout, for the error message.

    Raises
    ------
    FlicInputError
        When the file is missing or unreadable, or its size is not a multiple of ``record``.
    """
    try:
        with open_regular(path) as f:
            size = os.fstat(f.fileno()).st_size
            if size % record:
                raise FlicInputError(
                    path, f"size {size} bytes is not a multiple of {record} ({what})"
                )
            out = np.empty(size // np.dtype(dtype).itemsize, dtype=dtype)
            view = memoryview(out).cast("B")
            got = 0
            while got < size:
                n = f.readinto(view[got:])
                if not n:
                    raise FlicInputError(path, f"ended after {got} of {size} bytes while read")
                got += n
    except FileNotFoundError:
        raise FlicInputError(path, "does not exist") from None
    except OSError as exc:
        raise FlicInputError(path, f"cannot be read ({exc.strerror})") from None
    return out if out.dtype.isnative else out.astype(out.dtype.newbyteorder("="))


def read_bin(path: str | Path) -> np.ndarray:
    """Read a ``.bin`` scan as stored, without dropping anything.

    Parameters
    ----------
    path : the ``.bin`` file (little-endian float32 x, y, z in metres and remission per point).

    Returns
    -------
    (N, 4) float32 array, N >= 1.

    Raises
    ------
    FlicInputError
        When the file is missing, its size is not a multiple of 16 bytes or it holds no points.
    """
    data = _read_array(path, "<f4", 16, "x, y, z, remission float32")
    if not data.size:
        raise FlicInputError(path, "is empty (0 points)")
    return data.reshape(-1, 4)


def read_label(path: str | Path, n_points: int | None = None) -> np.ndarray:
    """Read a ``.label`` file.

    Parameters
    ----------
    path : the ``.label`` file (little-endian uint32 per point).
    n_points : the number of points of the scan the labels belong to; checked when given.

    Returns
    -------
    (N,) uint32 array (semantic class in the low 16 bits, instance id in the high 16 bits).

    Raises
    ------
    FlicInputError
        When the file is missing, its size is not a multiple of 4 bytes or the count differs from
        ``n_points``.
    """
    labels = _read_array(path, "<u4", 4, "one uint32 label per point")
    if n_points is not None and labels.size != n_points:
        raise FlicInputError(path, f"holds {labels.size} labels but the scan has {n_points} points")
    return labels


@njit(cache=True)
def _split_scan(flat: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """x, y, z as an (N, 3) array and the remission of ``(4N,)`` stored values, and the number of
    points with a NaN or infinite coordinate (``v - v`` is 0 exactly when ``v`` is finite)."""
    n = flat.size // 4
    xyz = np.empty(3 * n, dtype=flat.dtype)
    remission = np.empty(n, dtype=flat.dtype)
    bad = 0
    for i in range(n):
        x = flat[4 * i]
        y = flat[4 * i + 1]
        z = flat[4 * i + 2]
        xyz[3 * i] = x
        xyz[3 * i + 1] = y
        xyz[3 * i + 2] = z
        remission[i] = flat[4 * i + 3]
        bad += ((x - x) != 0) | ((y - y) != 0) | ((z - z) != 0)
    return xyz.reshape(n, 3), remission, bad


def read_scan(bin_path: str | Path, label_path: str | Path | None = None) -> Scan:
    """Read and validate a scan and, optionally, its labels.

    Points with a NaN or infinite coordinate are dropped, from the labels too, with a warning
    that counts them; ``Scan.finite`` says which points of the file were kept, so that outputs
    can still hold one value per point of the file.

    Parameters
    ----------
    bin_path : the ``.bin`` file.
    label_path : its ``.label`` file, or None.

    Returns
    -------
    Scan

    Raises
    ------
    FlicInputError
        On any problem of :func:`read_bin` or :func:`read_label`, or when no point has finite
        coordinates.
    """
    raw = read_bin(bin_path)
    labels = None if label_path is None else read_label(label_path, raw.shape[0])
    points, remission, n_bad = _split_scan(raw.reshape(-1))
    if n_bad == 0:  # the usual case: one pass, no mask
        return Scan(points, remission, labels, None)
    if n_bad == raw.shape[0]:
        raise FlicInputError(bin_path, f"none of its {n_bad} points has finite coordinates")
    warnings.warn(
        f"{bin_path}: dropped {n_bad} of {raw.shape[0]} points with NaN or infinite coordinates",
        stacklevel=2,
    )
    keep = np.isfinite(points).all(axis=1)
    return Scan(points[keep], remission[keep], None if labels is None else labels[keep], keep)


def write_bin(path: str | Path, points: np.ndarray) -> None:
    """Write a ``.bin`` scan atomically.

    Parameters
    ----------
    path : the file to write.
    points : (N, 3) or (N, 4) array: x, y, z in metres and, in the 4th column, remission (0 when
        absent).
    """
    points = np.asarray(points, dtype=np.float32)
    if points.ndim != 2 or points.shape[1] not in (3, 4):
        raise ValueError(f"points must have shape (N, 3) or (N, 4), got {points.shape}")
    out = np.zeros((points.shape[0], 4), dtype="<f4")
    out[:, : points.shape[1]] = points
    atomic_write_bytes(path, out.tobytes())


def write_label(path: str | Path, labels: np.ndarray) -> None:
    """Write (N,) encoded uint32 labels (:func:`flic_cli.labels.encode`) as a ``.label`` file
    atomically."""
    atomic_write_bytes(path, np.asarray(labels, dtype="<u4").tobytes())


# ---------------------------------------------------------------------------------------------
# Calibration and poses
# ---------------------------------------------------------------------------------------------


def _numbers(path: str | Path, lineno: int, tokens: list[str], what: str) -> np.ndarray:
    """Twelve numbers of one line as a (3, 4) float64 matrix."""
    if len(tokens) != 12:
        raise FlicInputError(path, f"line {lineno}: {what} has {len(tokens)} numbers, expected 12")
    values = []
    for token in tokens:
        try:
            values.append(float(token))
        except ValueError:
            raise FlicInputError(
                path, f"line {lineno}: {what}: {token!r} is not a number"
            ) from None
    return np.array(values).reshape(3, 4)


def read_calib(path: str | Path) -> dict[str, np.ndarray]:
    """Read a KITTI ``calib.txt``.

    Parameters
    ----------
    path : lines ``KEY: 12 numbers`` (``P0``..``P3`` camera projections, ``Tr`` velodyne to camera).

    Returns
    -------
    dict mapping each key to its (3, 4) float64 matrix (``Tr`` in metres).
    """
    calib: dict[str, np.ndarray] = {}
    for lineno, line in enumerate(read_text(path).splitlines(), start=1):
        if not line.strip():
            continue
        key, sep, rest = line.partition(":")
        if not sep or not key.strip():
            raise FlicInputError(path, f"line {lineno}: expected 'KEY: 12 numbers'")
        calib[key.strip()] = _numbers(path, lineno, rest.split(), key.strip())
    if not calib:
        raise FlicInputError(path, "holds no calibration entries")
    return calib


def write_calib(
    path: str | Path, calib: dict[str, np.ndarray], *, float_format: str = ".12e"
) -> None:
    """Write a KITTI ``calib.txt`` (each value a (3, 4) matrix) atomically.

    ``float_format`` is the format spec of every number (KITTI's own files use ``".6e"``).
    """
    lines = [
        f"{key}: "
        + " ".join(format(v, float_format) for v in np.asarray(m, dtype=np.float64).reshape(12))
        for key, m in calib.items()
    ]
    atomic_write_bytes(path, ("\n".join(lines) + "\n").encode())


def read_poses(path: str | Path) -> np.ndarray:
    """Read a KITTI ``poses.txt``: one 3x4 pose (12 numbers, row-major) per line.

    Returns
    -------
    (F, 3, 4) float64 array, translations in metres.
    """
    poses = [
        _numbers(path, lineno, line.split(), "pose")
        for lineno, line in enumerate(read_text(path).splitlines(), start=1)
        if line.strip()
    ]
    if not poses:
        raise FlicInputError(path, "holds no poses")
    return np.stack(poses)


def write_poses(path: str | Path, poses: np.ndarray, *, float_format: str = ".12e") -> None:
    """Write (F, 3, 4) poses as a KITTI ``poses.txt`` atomically.

    ``float_format`` is the format spec of every number (KITTI's own files use ``".6e"``).
    """
    poses = np.asarray(poses, dtype=np.float64)
    if poses.ndim != 3 or poses.shape[1:] != (3, 4):
        raise ValueError(f"poses must have shape (F, 3, 4), got {poses.shape}")
    text = "".join(" ".join(format(v, float_format) for v in p.reshape(12)) + "\n" for p in poses)
    atomic_write_bytes(path, text.encode())


def write_times(path: str | Path, times_s: np.ndarray, *, float_format: str = ".6e") -> None:
    """Write a KITTI ``times.txt`` atomically: one timestamp in seconds per line.

    ``float_format`` is the format spec of every number (default ``".6e"``, as KITTI's files).
    """
    times_s = np.asarray(times_s, dtype=np.float64)
    if times_s.ndim != 1:
        raise ValueError(f"times must have shape (F,), got {times_s.shape}")
    atomic_write_bytes(path, "".join(format(t, float_format) + "\n" for t in times_s).encode())


# ---------------------------------------------------------------------------------------------
# Predictions
# ---------------------------------------------------------------------------------------------


def predictions_path(out_root: str | Path, sequence: str, frame: int) -> Path:
    """``<out_root>/sequences/<sequence>/predictions/<frame:06d>.label``."""
    return Path(out_root) / "sequences" / sequence / "predictions" / f"{frame:06d}.label"


def export_path(out: Path, ref: FrameRef, suffix: str) -> Path:
    """Where a per-frame export of ``ref`` goes in the SemanticKITTI layout, shared by every
    format whose frames are a sequence (or recording, topic) and a number:
    ``<out>/sequences/<sequence>/<kind>/<frame:06d><suffix>``, ``kind`` the suffix without its
    dot (:meth:`flic_cli.io.base.Dataset.export_path`)."""
    kind = suffix.lstrip(".")
    return Path(out) / "sequences" / ref.sequence / kind / f"{ref.frame:06d}{suffix}"


def write_cluster_prediction(
    out: Path,
    ref: FrameRef,
    labels: np.ndarray,
    image: RangeImage | None = None,
    semantics: np.ndarray | None = None,
) -> Path:
    """:meth:`flic_cli.io.base.Dataset.write_prediction` of the formats whose predictions are
    SemanticKITTI ``.label`` files of cluster ids, one per point as read (``image`` unused):
    ``<out>/sequences/<sequence>/predictions/<frame:06d>.label`` (:func:`write_predictions`)."""
    return write_predictions(out, ref.sequence, ref.frame, labels, semantics)


def write_predictions(
    out_root: str | Path,
    sequence: str,
    frame: int,
    cluster_ids: np.ndarray,
    semantics: np.ndarray | None = None,
) -> Path:
    """Write one frame's predictions as a ``.label`` file.

    Parameters
    ----------
    out_root : the output root.
    sequence, frame : which frame.
    cluster_ids : (N,) integers in ``0..65535``, one per point of the scan, 0 = unclustered;
        written as they are to the upper 16 bits (the instance ids).
    semantics : (N,) raw SemanticKITTI class ids in ``0..65535``, written to the lower 16 bits;
        None (default) writes class 0 (unlabeled) for every point. To write a panoptic
        prediction (semantics, and instance ids that semantic-kitti-api scores as intended), use
        :func:`write_semantic_predictions`.

    Returns
    -------
    The written file (see :func:`predictions_path`).
    """
    ids = np.asarray(cluster_ids)
    sem = np.zeros_like(ids) if semantics is None else np.asarray(semantics)
    if sem.shape != ids.shape:
        raise ValueError(f"semantics has shape {sem.shape} but cluster_ids has shape {ids.shape}")
    path = predictions_path(out_root, sequence, frame)
    write_label(path, encode(sem, ids))
    return path


def read_predictions(
    out_root: str | Path,
    sequence: str,
    frame: int,
    n_points: int | None = None,
    semantics: bool = False,
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Read one frame's predictions written by :func:`write_predictions`.

    Parameters
    ----------
    out_root : the output root.
    sequence, frame : which frame.
    n_points : the number of points of the scan; checked when given.
    semantics : also return the semantic classes.

    Returns
    -------
    (N,) int32 cluster ids (upper 16 bits), 0 = unclustered; with ``semantics=True`` the tuple
    ``(cluster ids, (N,) int32 raw semantic class ids)``.
    """
    path = predictions_path(out_root, sequence, frame)
    labels = read_label(path, n_points)
    ids = instance(labels).astype(np.int32)
    if semantics:
        return ids, semantic(labels).astype(np.int32)
    return ids


# ---------------------------------------------------------------------------------------------
# Semantics (``flic segment --semantics``, see :mod:`flic_cli.semantics`)
# ---------------------------------------------------------------------------------------------


def semantics_path(root: str | Path, sequence: str, frame: int) -> Path:
    """``<root>/sequences/<sequence>/predictions/<frame:06d>.label`` (:mod:`flic_cli.semantics`)."""
    return predictions_path(root, sequence, frame)


def read_semantics(root: str | Path, sequence: str, frame: int, n_points: int) -> np.ndarray:
    """Read a semantic network's classes for one frame.

    Parameters
    ----------
    root : the ``--semantics`` folder (``<root>/sequences/<NN>/predictions/<XXXXXX>.label``).
    sequence, frame : which frame.
    n_points : number of points of the scan as stored in its ``.bin`` (one label each).

    Returns
    -------
    (N,) uint16 raw SemanticKITTI class ids (the lower 16 bits of each label).

    Raises
    ------
    FlicInputError
        Naming the file when it is missing, holds another number of labels than the scan has
        points, or holds a class that SemanticKITTI does not define.
    """
    path = semantics_path(root, sequence, frame)
    sem = semantic(read_label(path, n_points)).astype(np.uint16)
    unknown = np.unique(sem[~known_classes(sem)])
    if unknown.size:
        listed = ", ".join(str(int(u)) for u in unknown[:5])
        more = f" and {unknown.size - 5} more" if unknown.size > 5 else ""
        raise FlicInputError(
            path, f"holds semantic classes that SemanticKITTI does not define: {listed}{more}"
        )
    return sem


def write_semantic_predictions(
    out_root: str | Path,
    sequence: str,
    frame: int,
    semantics: np.ndarray,
    cluster_ids: np.ndarray,
) -> Path:
    """Write one frame's panoptic prediction: :func:`flic_cli.semantics.combine`, then
    :func:`write_predictions`.

    Parameters
    ----------
    out_root : the output root (``<out_root>/sequences/<NN>/predictions/<XXXXXX>.label``).
    sequence, frame : which frame.
    semantics : (N,) raw class ids, one per point of the scan as stored.
    cluster_ids : (N,) cluster ids (0 = unclustered), one per point of the scan as stored.

    Returns
    -------
    The written file.
    """
    labels = combine(semantics, cluster_ids)
    return write_predictions(out_root, sequence, frame, instance(labels), semantic(labels))


# ---------------------------------------------------------------------------------------------
# Dataset
# ---------------------------------------------------------------------------------------------


def is_semantickitti(path: Path) -> bool:
    """True when ``path`` is a SemanticKITTI root (``sequences/``) or sequence (``velodyne/``)."""
    return (path / "sequences").is_dir() or (path / "velodyne").is_dir()


def _sequence_dirs(root: Path) -> dict[str, Path]:
    """The sequences of a root (its ``sequences/*`` with ``velodyne/``) or the sequence itself."""
    if (root / "velodyne").is_dir():
        return {root.name: root}
    return {d.name: d for d in sorted((root / "sequences").iterdir()) if (d / "velodyne").is_dir()}


class SemanticKittiDataset:
    """A SemanticKITTI dataset root or sequence folder (implements :class:`Dataset`).

    Parameters
    ----------
    root : a folder with ``sequences/<NN>/velodyne/`` or a single sequence folder with
        ``velodyne/`` (its sequence name is the folder's name).
    sequences : the sequences to use (``["00", "08"]``); None = all.
    frames : ``(start, stop)`` frame numbers, start inclusive, stop exclusive, either None for
        open; None = all frames.
    require_labels : fail when a selected frame has no ``labels/<XXXXXX>.label``. Without an
        explicit ``sequences`` selection, sequences that have no ``labels/`` folder at all (the
        unlabelled test split 11-21) are left out with a warning instead.

    Raises
    ------
    FlicInputError
        When a requested sequence does not exist, no frame is selected or labels are missing
        although required.
    """

    format = FORMAT
    point_semantics = True
    detect = staticmethod(is_semantickitti)

    def __init__(
        self,
        root: str | Path,
        sequences: list[str] | None = None,
        frames: tuple[int | None, int | None] | None = None,
        require_labels: bool = False,
    ) -> None:
        self.root = Path(root)
        if not is_semantickitti(self.root):
            raise FlicInputError(
                self.root, "is not a SemanticKITTI root or sequence (no sequences/ or velodyne/)"
            )
        found = _sequence_dirs(self.root)
        if not found:
            raise FlicInputError(self.root, "has no sequences/<NN>/velodyne/ folders")
        found = select_sequences(self.root, found, sequences)
        if sequences is None and require_labels:
            # A whole dataset: leave out the sequences without labels (SemanticKITTI's test split).
            unlabelled = [s for s, d in found.items() if not (d / "labels").is_dir()]
            if unlabelled and len(unlabelled) < len(found):
                warnings.warn(
                    f"{self.root}: sequences {', '.join(unlabelled)} have no labels/ folder "
                    "(unlabelled split) and are left out",
                    stacklevel=2,
                )
                found = {s: d for s, d in found.items() if s not in unlabelled}
        self._refs: list[FrameRef] = []
        for name, seq_dir in found.items():
            seen: dict[int, Path] = {}
            for bin_path in sorted((seq_dir / "velodyne").glob("*.bin")):
                if not bin_path.stem.isdigit():
                    continue
                if not bin_path.stem.isascii():  # e.g. "00①" or Arabic-Indic digits
                    warnings.warn(
                        f"{bin_path}: left out: frame numbers are written in the digits 0-9",
                        stacklevel=2,
                    )
                    continue
                number = int(bin_path.stem)
                if number in seen:
                    raise FlicInputError(
                        bin_path,
                        f"names frame {number} like {seen[number].name}: keep one of the two files",
                    )
                seen[number] = bin_path
                if not in_frames(number, frames):
                    continue
                label_path = seq_dir / "labels" / f"{bin_path.stem}.label"
                self._refs.append(
                    FrameRef(
                        name,
                        int(bin_path.stem),
                        bin_path,
                        label_path if label_path.is_file() else None,
                        FORMAT,
                    )
                )
        if not self._refs:
            what = "" if frames is None else f" in frames {frames_text(frames)}"
            raise FlicInputError(
                self.root, f"no scans (velodyne/*.bin){what} in sequences {', '.join(found)}"
            )
        missing = [r for r in self._refs if r.label_path is None]
        if require_labels and missing:
            names = ", ".join(
                str((r.path.parents[1] / "labels" / f"{r.path.stem}.label").relative_to(self.root))
                for r in missing[:3]
            )
            more = f" and {len(missing) - 3} more" if len(missing) > 3 else ""
            raise FlicInputError(self.root, f"missing label files: {names}{more}")

    def refs(self) -> list[FrameRef]:
        """Every selected frame, ordered by sequence then frame number."""
        return list(self._refs)

    def labelled(self) -> bool:
        """Whether some selected frame has a ``labels/<XXXXXX>.label`` file."""
        return any(r.label_path is not None for r in self._refs)

    def folders(self) -> list[Path]:
        """The folders of the selected sequences (outputs must not go inside them)."""
        return sorted({r.path.parents[1] for r in self._refs})

    @staticmethod
    def write_prediction(
        out: Path,
        ref: FrameRef,
        labels: np.ndarray,
        image: RangeImage | None = None,
        semantics: np.ndarray | None = None,
    ) -> Path:
        """Write one frame's prediction: ``<out>/sequences/NN/predictions/XXXXXX.label``.

        Parameters
        ----------
        labels : (N,) cluster ids, one per point of the ``.bin`` (0 = unclustered).
        image : unused (the points carry their labels).
        semantics : (N,) raw classes to write with them (see :mod:`flic_cli.semantics`), or
            None: semantic class 0.
        """
        if semantics is None:
            return write_predictions(out, ref.sequence, ref.frame, labels)
        return write_semantic_predictions(out, ref.sequence, ref.frame, semantics, labels)

    export_path = staticmethod(export_path)

    def load(self, ref: FrameRef) -> Frame:
        """Read one frame (points with non-finite coordinates dropped, with a warning)."""
        scan = read_scan(ref.path, ref.label_path)
        stored = None
        if scan.finite is not None and ref.label_path is not None:  # rare: re-read all labels
            stored = read_label(ref.label_path, scan.finite.size)
        return Frame(ref, scan.points, scan.labels, finite=scan.finite, stored_labels=stored)
