"""The chain every run uses: frame -> range image -> ground extraction -> clusterer -> labels.

``prepare`` turns a loaded frame into the evaluated point set and its range image (the "No Ground"
setting drops the ground classes' points by label first); a :class:`Segmenter` runs one method,
with the chosen ground remover, on a prepared frame. Runs (segment, evaluate, benchmark, sweep)
differ only in what they do with the labels.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from flic_cli.classes import ground_mask
from flic_cli.config import build_method, method_ground
from flic_cli.errors import FlicInputError
from flic_cli.io.base import Frame, FrameRef
from flic_cli.range_image import RangeImage, project_points

SETTINGS = ("ground", "no-ground")


@dataclass
class Prepared:
    """A frame ready for the methods.

    Attributes
    ----------
    ref : the frame's reference
    image : range image of the evaluated point set
    points : (N, 3) float32, the evaluated point set
    labels : (N,) uint32 ground-truth labels of the evaluated points, or None
    keep : (N_scan,) bool, which points of the scan as stored in its file are evaluated (None =
        all): not those with non-finite coordinates, nor, in the no-ground setting, ground points
    n_scan : number of points of the scan as stored in its file
    """

    ref: FrameRef
    image: RangeImage
    points: np.ndarray
    labels: np.ndarray | None
    keep: np.ndarray | None
    n_scan: int

    def scan_labels(self, labels: np.ndarray) -> np.ndarray:
        """Labels of the evaluated points expanded to every point of the scan (0 = dropped)."""
        if self.keep is None:
            return labels
        out = np.zeros(self.n_scan, dtype=labels.dtype)
        out[self.keep] = labels
        return out


def prepare(frame: Frame, setting: str, projection: dict[str, Any]) -> Prepared:
    """Project a frame for the given setting.

    Parameters
    ----------
    frame : a loaded frame.
    setting : ``"ground"`` (all points; methods extract the ground themselves) or ``"no-ground"``
        (the ground classes' points are removed by label, the paper's "No Ground" column).
    projection : the ``[projection]`` table of the config (width, mode, rows, fov).
    """
    if setting not in SETTINGS:
        raise FlicInputError(None, f"--setting must be one of {', '.join(SETTINGS)}")
    points, labels, keep = frame.points, frame.labels, None
    if setting == "no-ground":
        if labels is None:
            raise FlicInputError(
                frame.ref.path,
                "the no-ground setting removes the ground classes by label, and this frame has "
                "no labels (use --setting ground)",
            )
        keep = ~ground_mask(labels)
    if frame.image is not None and keep is None:
        image = frame.image
    elif frame.image is not None:  # a sensor image with some points removed
        pix = frame.image.point_pixel[keep]
        ranges = np.zeros(frame.image.ranges.size, dtype=np.float32)
        ranges[pix] = frame.image.ranges.reshape(-1)[pix]
        image = RangeImage(
            ranges.reshape(frame.image.ranges.shape), frame.image.elevation, pix, "native"
        )
    else:
        image = project_points(
            points,
            width=int(projection.get("width", 2048)),
            mode=str(projection.get("mode", "rings")),
            rows=int(projection.get("rows", 64)),
            fov_up_deg=float(projection.get("fov_up_deg", 3.0)),
            fov_down_deg=float(projection.get("fov_down_deg", -25.0)),
            keep=keep,
        )
    if keep is not None:
        points, labels = points[keep], labels[keep]
    return Prepared(frame.ref, image, points, labels, _in_file(frame.finite, keep), frame.n_read)


def _in_file(finite: np.ndarray | None, keep: np.ndarray | None) -> np.ndarray | None:
    """``keep`` (over the finite points) as a mask over every point of the file."""
    if finite is None:
        return keep
    if keep is None:
        return finite
    out = finite.copy()
    out[np.flatnonzero(finite)[~keep]] = False
    return out


@dataclass(frozen=True)
class Segmenter:
    """One method with its ground remover: ``segmenter(image, points) -> (labels, ground)``.

    Attributes
    ----------
    name : the method variant's name in the config (e.g. ``"flic14"``)
    method : the clusterer (see :mod:`flic_cli.methods`)
    ground_name : the remover's name (``"paper"``, ...), None in the "No Ground" setting
    remover : the ground remover (see :mod:`flic_cli.ground`), None in the "No Ground" setting
    """

    name: str
    method: Any
    ground_name: str | None
    remover: Any

    def extract_ground(self, image: RangeImage, points: np.ndarray) -> np.ndarray | None:
        """The remover's (H, W) ground mask, or None when there is no remover."""
        return None if self.remover is None else self.remover(image, points)

    def __call__(self, image: RangeImage, points: np.ndarray) -> tuple[np.ndarray, Any]:
        """Per-point labels (0 = none) and the ground mask used (or None)."""
        ground = self.extract_ground(image, points)
        return self.method.segment(image, points, ground), ground

    def with_param(self, value: float) -> Segmenter:
        """The same segmenter with the method's main parameter (sweeps) set to ``value``."""
        method = replace(self.method, **{self.method.main_param: value})
        return replace(self, method=method)


def make_segmenter(
    cfg: dict[str, Any], name: str, setting: str, ground_remover: str = "paper"
) -> Segmenter:
    """Build the segmenter of method variant ``name``.

    Parameters
    ----------
    cfg : the loaded config.
    name : a ``[methods.NAME]`` variant.
    setting : ``"ground"`` or ``"no-ground"`` (no remover runs in the latter).
    ground_remover : ``"paper"`` (every method uses the paper's ground extraction: the paper's
        protocol), ``"own"`` (each method its own ``ground`` key: Bogoslavskyi uses theirs) or a
        remover's name.
    """
    from flic_cli.config.component import describe
    from flic_cli.ground import REMOVERS

    method = build_method(cfg, name)
    if setting == "no-ground":
        return Segmenter(name, method, None, None)
    remover = method_ground(cfg, name) if ground_remover == "own" else ground_remover
    if remover not in REMOVERS:
        raise FlicInputError(
            None, f"unknown ground remover {remover!r} ({' | '.join(REMOVERS)} | own)"
        )
    params = dict(cfg.get("ground", {}).get(remover, {}))
    try:
        built = REMOVERS[remover](**params)
    except (TypeError, ValueError) as exc:
        raise FlicInputError(None, f"[ground.{remover}] {describe(exc)}") from None
    return Segmenter(name, method, remover, built)


def resolve_method(method: str, mc: int | None) -> str:
    """``--method flic --mc 14`` -> ``"flic14"``; other names pass through."""
    if mc is not None:
        if method != "flic":
            raise FlicInputError(None, "--mc applies to --method flic only")
        return f"flic{mc}"
    return "flic0" if method == "flic" else method


def parse_methods(text: str, cfg: dict[str, Any]) -> list[str]:
    """Comma-separated method variant names, checked against the config."""
    names = [t.strip() for t in text.split(",") if t.strip()]
    unknown = [n for n in names if n not in cfg.get("methods", {})]
    if unknown or not names:
        raise FlicInputError(
            None,
            f"unknown method {', '.join(unknown) or '(none)'} "
            f"(known: {', '.join(cfg.get('methods', {}))})",
        )
    return names
