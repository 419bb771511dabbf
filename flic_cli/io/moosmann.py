"""Moosmann-style logs: 16-bit greyscale PNG range images plus ``img.cfg`` (docs/specification.md).

A log is a folder with ``scanNNNNN.png`` files (directly or in a ``range/`` subfolder) and an
``img.cfg`` (in the log folder, or beside the PNGs). Pixel value / 500 = range in metres,
0 = no measurement. Frames may be missing (gaps in the numbering) or empty.
"""

from __future__ import annotations

import io
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from flic_cli.errors import FlicInputError
from flic_cli.io.atomic import atomic_write, atomic_write_bytes, read_bytes, read_text
from flic_cli.io.base import Frame, FrameRef, frames_text, in_frames, select_sequences
from flic_cli.range_image import RangeImage, from_sensor_image_with_points

FORMAT = "moosmann"
RANGE_SCALE = 500.0
"""PNG pixel value per metre (1 unit = 2 mm)."""
_PNG_MAX = int(np.iinfo(np.uint16).max)
"""Largest value of a 16-bit PNG pixel."""

_SCAN_NAME = re.compile(r"scan([0-9]+)\.png")  # ASCII digits only (not \d: other scripts' digits)
_NOT_ASCII = "left out: frame numbers are written in the digits 0-9"
_PNG_COLOUR_TYPES = {
    0: "greyscale",
    2: "RGB",
    3: "palette",
    4: "greyscale with alpha",
    6: "RGBA",
}  # IHDR colour type -> name


@dataclass(frozen=True, eq=False)
class ImgCfg:
    """The content of an ``img.cfg``.

    Attributes
    ----------
    width, height : image size in pixels (870 x 64 for the HDL-64E logs).
    h_start_deg, h_stop_deg : yaw of the first and last column in degrees (180, -180).
    pitch_deg : (height,) float64 pitch of every row in degrees, positive = downward.
    """

    width: int
    height: int
    h_start_deg: float
    h_stop_deg: float
    pitch_deg: np.ndarray

    def elevation(self) -> np.ndarray:
        """(height,) elevation of every row in radians, positive up (= -pitch)."""
        return np.radians(-np.asarray(self.pitch_deg, dtype=np.float64))


def read_img_cfg(path: str | Path) -> ImgCfg:
    """Read an ``img.cfg``.

    Lines starting with ``#`` are comments; the data (which may span lines) is ``;``-separated:
    ``width; height; h_start; h_stop; pitch_1; ...; pitch_height`` (angles in degrees); a
    trailing ``;`` is allowed.

    Raises
    ------
    FlicInputError
        When the file is missing, a field is not a number, the size is not positive integers or
        the number of pitch angles differs from the height.
    """
    data = ";".join(
        line for line in read_text(path).splitlines() if not line.lstrip().startswith("#")
    )
    fields = [f.strip() for f in data.split(";") if f.strip()]
    if len(fields) < 4:
        raise FlicInputError(
            path, f"has {len(fields)} fields, expected width; height; h_start; h_stop; angles..."
        )
    values = []
    for i, field in enumerate(fields, start=1):
        try:
            values.append(float(field))
        except ValueError:
            raise FlicInputError(path, f"field {i} {field!r} is not a number") from None
        if not np.isfinite(values[-1]):
            raise FlicInputError(path, f"field {i} {field!r} is not a finite number")
    for name, v in (("width", values[0]), ("height", values[1])):
        if v != int(v) or v < 1:
            raise FlicInputError(path, f"image {name} {v:g} is not a positive integer")
    width, height = int(values[0]), int(values[1])
    pitch = np.array(values[4:], dtype=np.float64)
    if pitch.size != height:
        raise FlicInputError(path, f"declares {height} rows but lists {pitch.size} vertical angles")
    return ImgCfg(width, height, values[2], values[3], pitch)


def write_img_cfg(
    path: str | Path,
    cfg: ImgCfg,
    *,
    comment: str | None = None,
    pitch_format: str | None = None,
) -> None:
    """Write an ``img.cfg`` atomically (one comment line, one data line).

    Parameters
    ----------
    path : the file to write.
    cfg : its content. The horizontal angles are written with ``repr``: integers (``180``) as
        integers, floats (``180.0``) as floats.
    comment : text of the comment line (after ``# ``); None = the names of the fields.
    pitch_format : format spec of the vertical angles, e.g. ``".4f"`` (4 decimals, as the real
        files have); None = ``repr`` (exact round trip).
    """
    if comment is None:
        comment = (
            "imgHSize; imgVSize; horizStartAngle; horizStopAngle; vertAngle_1; ...; vertAngle_n"
        )
    fields = [str(cfg.width), str(cfg.height), repr(cfg.h_start_deg), repr(cfg.h_stop_deg)]
    fields += [
        repr(float(a)) if pitch_format is None else format(float(a), pitch_format)
        for a in cfg.pitch_deg
    ]
    text = f"# {comment}\n" + "; ".join(fields) + ";\n"
    atomic_write_bytes(path, text.encode())


def _read_png16(path: str | Path, size: tuple[int, int], expected: str) -> np.ndarray:
    """Pixels of a 16-bit greyscale PNG of ``size = (width, height)`` pixels, checked.

    ``expected`` says where the size comes from, for the error message.
    """
    data = read_bytes(path)
    try:
        with Image.open(io.BytesIO(data)) as img:
            img.load()
            fmt, got = img.format, img.size
            pixels = np.asarray(img)
    except UnidentifiedImageError:
        raise FlicInputError(path, "is not an image Pillow can decode, expected a PNG") from None
    except (OSError, SyntaxError, ValueError) as exc:
        raise FlicInputError(path, f"cannot be decoded ({exc})") from None
    if fmt != "PNG":
        raise FlicInputError(path, f"is a {fmt} image, expected a 16-bit greyscale PNG")
    # The IHDR chunk comes first: bytes 24 and 25 are the bit depth and the colour type.
    depth, colour = data[24], data[25]
    if (depth, colour) != (16, 0):
        raise FlicInputError(
            path,
            f"is {depth}-bit {_PNG_COLOUR_TYPES.get(colour, f'colour type {colour}')}, "
            "expected 16-bit greyscale",
        )
    if got != size:
        raise FlicInputError(path, f"is {got[0]}x{got[1]} but {expected} {size[0]}x{size[1]}")
    return pixels


def read_png_range(path: str | Path, cfg: ImgCfg) -> np.ndarray:
    """Read a 16-bit greyscale PNG range image.

    Parameters
    ----------
    path : the ``scanNNNNN.png`` file.
    cfg : the log's ``img.cfg``; the image must have its size.

    Returns
    -------
    (height, width) float32 ranges in metres (pixel value / 500), 0 = no measurement.

    Raises
    ------
    FlicInputError
        When the file is missing, not a decodable PNG, not 16-bit greyscale or not of the size
        that ``img.cfg`` declares.
    """
    ranges = _read_png16(path, (cfg.width, cfg.height), "img.cfg says").astype(np.float32)
    ranges /= np.float32(RANGE_SCALE)
    return ranges


def write_png_range(path: str | Path, ranges_m: np.ndarray) -> None:
    """Write ranges as a 16-bit greyscale PNG atomically.

    Parameters
    ----------
    path : the file to write.
    ranges_m : (H, W) ranges in metres; stored as ``round(range * 500)`` clipped to 65535
        (131.07 m); 0, negative and non-finite values are stored as 0 (no measurement).
    """
    r = np.asarray(ranges_m, dtype=np.float64)
    r = np.where(np.isfinite(r) & (r > 0), r, 0.0)
    pixels = np.clip(np.rint(r * RANGE_SCALE), 0, _PNG_MAX).astype("<u2")
    with atomic_write(path) as tmp:
        Image.fromarray(pixels).save(tmp, format="PNG")


# ---------------------------------------------------------------------------------------------
# Predictions as label images
# ---------------------------------------------------------------------------------------------

LABEL_IMAGE_SUFFIX = ".label.png"
"""Suffix of a label image: ``scan00012.png`` -> ``scan00012.label.png``."""


def label_image_path(out_root: str | Path, log: str, range_image: str | Path) -> Path:
    """Where the predictions of a Moosmann range image go: ``<out_root>/<log>/<name>.label.png``.

    The label image is named after its range image (``scan00012.png`` ->
    ``scan00012.label.png``, the digits as in the log) in a folder named after the log. The
    double suffix keeps it from being taken for a range image (``scanNNNNN.png``) when the output
    folder is read as a log.

    Parameters
    ----------
    out_root : the output root.
    log : the log's name (its folder's name, the ``sequence`` of its frames).
    range_image : the range image's path or file name.
    """
    return Path(out_root) / log / (Path(range_image).stem + LABEL_IMAGE_SUFFIX)


def label_image(point_pixel: np.ndarray, labels: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Per-point labels as an image: every pixel holds the label of its points, 0 elsewhere.

    Parameters
    ----------
    point_pixel : (N,) flat pixel index of every point (``RangeImage.point_pixel``; -1 = none).
    labels : (N,) cluster ids of the points (values <= 0 = none); points that share a pixel
        share its cluster id, and the last such point's id is kept.
    shape : (height, width) of the range image.

    Returns
    -------
    (height, width) int64 image, 0 = no measurement or no cluster.
    """
    pix = np.asarray(point_pixel, dtype=np.int64)
    lab = np.asarray(labels, dtype=np.int64)
    if pix.shape != lab.shape:
        raise ValueError(f"point_pixel and labels differ in shape: {pix.shape}, {lab.shape}")
    out = np.zeros(shape[0] * shape[1], dtype=np.int64)
    has = pix >= 0
    out[pix[has]] = np.maximum(lab[has], 0)
    return out.reshape(shape)


def write_label_image(path: str | Path, labels: np.ndarray) -> Path:
    """Write a label image as a 16-bit greyscale PNG atomically (Pillow).

    Parameters
    ----------
    path : the file to write (see :func:`label_image_path`).
    labels : (H, W) integer cluster ids in ``0..65535`` (0 = none), the size of the range image.

    Returns
    -------
    The written file.

    Raises
    ------
    ValueError
        When ``labels`` is not a 2-D integer array or holds an id outside ``0..65535``.
    """
    lab = np.asarray(labels)
    if lab.ndim != 2 or not np.issubdtype(lab.dtype, np.integer):
        raise ValueError(f"labels must be a 2-D integer array, got {lab.dtype} {lab.shape}")
    if lab.size and (lab.min() < 0 or lab.max() > _PNG_MAX):
        raise ValueError(
            f"cluster ids must lie in 0..65535 to fit a 16-bit PNG, got {lab.min()}..{lab.max()}"
        )
    path = Path(path)
    with atomic_write(path) as tmp:
        Image.fromarray(lab.astype("<u2")).save(tmp, format="PNG")
    return path


def read_label_image(path: str | Path, cfg: ImgCfg) -> np.ndarray:
    """Read a label image written by :func:`write_label_image`.

    Parameters
    ----------
    path : the ``.label.png`` file.
    cfg : the log's ``img.cfg``; the image must have its size.

    Returns
    -------
    (height, width) int32 cluster ids, 0 = none.

    Raises
    ------
    FlicInputError
        When the file is missing, not a 16-bit greyscale PNG or not of the log's image size.
    """
    return _read_png16(path, (cfg.width, cfg.height), "img.cfg says").astype(np.int32)


# ---------------------------------------------------------------------------------------------
# Dataset
# ---------------------------------------------------------------------------------------------


def _scan_frames(folder: Path) -> dict[int, Path]:
    """``scanNNNNN.png`` files of a folder by frame number (ASCII digits; other names are not
    frames).

    Raises
    ------
    FlicInputError
        When two files name the same frame number (``scan0001.png`` and ``scan00001.png``): the
        frame would be counted twice and its predictions overwritten.
    """
    out: dict[int, Path] = {}
    for p in sorted(folder.glob("scan*.png")):
        m = _SCAN_NAME.fullmatch(p.name)
        if m is None and re.fullmatch(r"scan\d+\.png", p.name):
            warnings.warn(f"{p}: {_NOT_ASCII}", stacklevel=2)
        if m:
            frame = int(m.group(1))
            if frame in out:
                raise FlicInputError(
                    p, f"names frame {frame} like {out[frame].name}: keep one of the two files"
                )
            out[frame] = p
    return dict(sorted(out.items()))


def _log_layout(folder: Path) -> tuple[Path, Path] | None:
    """``(scans folder, img.cfg)`` of a log folder, or None when ``folder`` is no log.

    A log holds ``scan*.png`` directly or in ``range/``, and an ``img.cfg`` beside the PNGs or in
    the folder above them. A folder with ``img.cfg`` but no scans is a log without frames.
    """
    if _scan_frames(folder) and _scan_frames(folder / "range"):
        raise FlicInputError(
            folder,
            "holds scan*.png range images both directly and in range/: which are the log's is "
            "unclear, keep them in one of the two folders",
        )
    for scans in (folder, folder / "range"):
        if _scan_frames(scans):
            for cfg in (scans / "img.cfg", scans.parent / "img.cfg"):
                if cfg.is_file():
                    return scans, cfg
            raise FlicInputError(
                folder,
                f"holds scan*.png range images but no img.cfg "
                f"(looked in {scans} and {scans.parent})",
            )
    if (folder / "img.cfg").is_file():
        return folder, folder / "img.cfg"
    return None


def is_moosmann(path: Path) -> bool:
    """True when ``path`` is a Moosmann log or a folder of logs."""
    if not path.is_dir():
        return False
    return _log_layout(path) is not None or any(
        d.is_dir() and _log_layout(d) is not None for d in path.iterdir()
    )


def _log_name(scans: Path) -> str:
    return _log_dir(scans).name


def _log_dir(scans: Path) -> Path:
    """The log folder of a folder of scans (the scans may sit in its ``range/``)."""
    return scans.parent if scans.name == "range" else scans


class MoosmannDataset:
    """A Moosmann log or a folder of logs (implements :class:`Dataset`).

    Parameters
    ----------
    root : a log folder, a log's ``range/`` folder, or a folder whose subfolders are logs (the
        sequence name of a log is its folder's name).
    sequences : the logs to use; None = all.
    frames : ``(start, stop)`` frame numbers, start inclusive, stop exclusive, either None for
        open; None = all frames.

    Raises
    ------
    FlicInputError
        When ``root`` holds no log, a requested log does not exist, an ``img.cfg`` is missing or
        malformed, or no frame is selected.
    """

    format = FORMAT
    point_semantics = False
    detect = staticmethod(is_moosmann)

    def __init__(
        self,
        root: str | Path,
        sequences: list[str] | None = None,
        frames: tuple[int | None, int | None] | None = None,
        require_labels: bool = False,
    ) -> None:
        if require_labels:
            raise FlicInputError(root, "is a Moosmann log, which has no ground-truth labels")
        self.root = Path(root)
        if not self.root.is_dir():
            raise FlicInputError(self.root, "is not a folder")
        layout = _log_layout(self.root)
        if layout is not None:
            logs = {_log_name(layout[0]): layout}
        else:
            candidates = sorted(d for d in self.root.iterdir() if d.is_dir())
            logs = {d.name: lay for d in candidates if (lay := _log_layout(d)) is not None}
        if not logs:
            raise FlicInputError(self.root, "holds no Moosmann log (img.cfg + scan*.png)")
        logs = select_sequences(self.root, logs, sequences)
        self._cfg: dict[str, ImgCfg] = {}
        self._refs: list[FrameRef] = []
        for name, (scans, cfg_path) in logs.items():
            cfg = read_img_cfg(cfg_path)
            if (cfg.h_start_deg, cfg.h_stop_deg) != (180.0, -180.0):
                raise FlicInputError(
                    cfg_path,
                    f"horizontal angles {cfg.h_start_deg:g}; {cfg.h_stop_deg:g} are not "
                    "supported (only a full turn: 180; -180)",
                )
            self._cfg[name] = cfg
            self._refs += [
                FrameRef(name, frame, path, None, FORMAT)
                for frame, path in _scan_frames(scans).items()
                if in_frames(frame, frames)
            ]
        if not self._refs:
            what = "" if frames is None else f" in frames {frames_text(frames)}"
            raise FlicInputError(self.root, f"no scan*.png frames{what} in logs {', '.join(logs)}")

    def refs(self) -> list[FrameRef]:
        """Every selected frame, ordered by log then frame number."""
        return list(self._refs)

    @staticmethod
    def labelled() -> bool:
        """False: a Moosmann log has no ground-truth labels."""
        return False

    def folders(self) -> list[Path]:
        """The folders of the selected logs (outputs must not go inside them)."""
        return sorted({_log_dir(r.path.parent) for r in self._refs})

    @staticmethod
    def write_prediction(
        out: Path,
        ref: FrameRef,
        labels: np.ndarray,
        image: RangeImage | None = None,
        semantics: np.ndarray | None = None,
    ) -> Path:
        """Write one frame's prediction as a label image (:func:`label_image_path`).

        Parameters
        ----------
        labels : (N,) cluster ids of the frame's points, i.e. of its valid pixels in row-major
            order (0 = unclustered).
        image : the frame's range image (its ``point_pixel`` and shape place the labels).
        semantics : must be None (a Moosmann log has no semantic classes).
        """
        if image is None or semantics is not None:
            raise ValueError("a Moosmann prediction needs the range image and takes no semantics")
        path = label_image_path(out, ref.sequence, ref.path)
        return write_label_image(path, label_image(image.point_pixel, labels, image.shape))

    @staticmethod
    def export_path(out: Path, ref: FrameRef, suffix: str) -> Path:
        """Where a per-frame export goes: ``<out>/<log>/scanNNNNN<suffix>``."""
        return Path(out) / ref.sequence / (Path(ref.path).stem + suffix)

    def load(self, ref: FrameRef) -> Frame:
        """Read one frame; an all-zero image gives a frame with 0 points.

        ``points[i]`` is the point of pixel ``image.point_pixel[i]`` (row-major pixel order).
        """
        cfg = self._cfg[ref.sequence]
        image, points = from_sensor_image_with_points(
            read_png_range(ref.path, cfg), cfg.elevation()
        )
        return Frame(ref, points, None, image)
