"""The chain every run uses: frame -> range image -> ground extraction -> clusterer -> labels.

:func:`prepare` turns a loaded frame into the evaluated point set and its range image (the "No
Ground" setting drops the ground classes' points by label first); a :class:`Segmenter`, built once
per run by :func:`build_segmenter`, runs one method with its ground remover on a prepared frame.
Runs (segment, evaluate, benchmark, sweep) differ only in what they do with the labels.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from flic_cli import registry
from flic_cli.classes import ground_mask
from flic_cli.component import check_installed
from flic_cli.config import Config
from flic_cli.errors import FlicInputError
from flic_cli.ground.base import Ground
from flic_cli.io.base import Frame, FrameRef
from flic_cli.projection import Projection
from flic_cli.range_image import RangeImage, sensor_subset

#: The paper's two settings: each method after ground extraction (no labels used), or with the
#: ground classes' points removed by label first.
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


def check_setting(setting: str) -> str:
    """``setting`` if it is one of :data:`SETTINGS`, else a one-line error."""
    if setting not in SETTINGS:
        raise FlicInputError(None, f"--setting must be one of {', '.join(SETTINGS)}")
    return setting


def prepare(
    frame: Frame, setting: str, projection: Projection, only: np.ndarray | None = None
) -> Prepared:
    """Project a frame for the given setting.

    Parameters
    ----------
    frame : a loaded frame.
    setting : ``"ground"`` (all points; methods extract the ground themselves) or ``"no-ground"``
        (the ground classes' points are removed by label, the paper's "No Ground" column).
    projection : how a SemanticKITTI scan becomes a range image (Moosmann frames are images).
    only : (N,) bool over ``frame.points``: evaluate these points only (e.g. the thing classes of
        a semantic segmentation); rows are still recovered from the whole scan.

    Warns
    -----
    UserWarning
        Naming the scan, when ring recovery fails and the spherical projection is used instead.
    """
    check_setting(setting)
    points, labels, keep = frame.points, frame.labels, None
    if setting == "no-ground":
        if labels is None:
            raise FlicInputError(
                frame.ref.path,
                "the no-ground setting removes the ground classes by label, and this frame has "
                "no labels (use --setting ground)",
            )
        keep = ~ground_mask(labels)
    if only is not None:
        keep = only if keep is None else keep & only
    if frame.image is not None and keep is None:
        image = frame.image
    elif frame.image is not None:  # a sensor image with some points removed
        image = sensor_subset(frame.image, keep)
    else:
        image = projection(points, keep)
        if projection.mode == "rings" and image.projection == "spherical":
            warnings.warn(
                f"{frame.ref.path}: ring recovery did not find {projection.rows} rings in scan "
                "order; this scan uses a spherical projection",
                stacklevel=2,
            )
    if keep is not None:
        points, labels = points[keep], labels[keep]
    return Prepared(frame.ref, image, points, labels, _in_file(frame.finite, keep), frame.n_read)


def scan_semantics(frame: Frame, semantics: str) -> np.ndarray:
    """(N_scan,) raw semantic class of every point of the scan as stored.

    Parameters
    ----------
    frame : a frame of a dataset with ``point_semantics`` (with labels for ``"oracle"``).
    semantics : ``"oracle"`` (the ground truth's classes) or a folder of a semantic network's
        predictions (see :mod:`flic_cli.semantics`).
    """
    from flic_cli.io.semantickitti import read_semantics
    from flic_cli.semantics import oracle_semantics

    ref = frame.ref
    if semantics != "oracle":
        return read_semantics(semantics, ref.sequence, ref.frame, frame.n_read)
    labels = frame.labels_as_stored()  # the dropped points' too
    if labels is None:
        raise FlicInputError(ref.path, "--semantics oracle needs the frame's labels")
    return oracle_semantics(labels)


def prepare_semantic(frame: Frame, semantics: np.ndarray, projection: Projection) -> Prepared:
    """The frame's points of thing classes, ready for clustering ("semantic network +
    clustering": the semantic classes decide what is an object, the method separates them).

    Parameters
    ----------
    frame : a loaded frame.
    semantics : (N_scan,) raw classes of every point as stored (:func:`scan_semantics`).
    projection : as for :func:`prepare`.
    """
    from flic_cli.semantics import cluster_mask

    finite = semantics if frame.finite is None else semantics[frame.finite]
    return prepare(frame, "ground", projection, only=cluster_mask(finite))


def _in_file(finite: np.ndarray | None, keep: np.ndarray | None) -> np.ndarray | None:
    """``keep`` (over the finite points) as a mask over every point of the file."""
    if finite is None:
        return keep
    if keep is None:
        return finite
    out = finite.copy()
    out[np.flatnonzero(finite)[~keep]] = False
    return out


def needs_semantics(method: Any) -> bool:
    """Whether ``method`` clusters per semantic class (declares ``needs_semantics``, e.g.
    :class:`flic_cli.methods.alpine.Alpine`): it then takes ``semantics=`` in ``segment``."""
    return bool(getattr(method, "needs_semantics", False))


def uses_semantics(method: Any) -> bool:
    """Whether ``method`` uses the semantic classes when a run has them (``--semantics``) and
    clusters without them otherwise (declares ``uses_semantics``, e.g.
    :class:`flic_cli.methods.bridge.Bridge`), or needs them (:func:`needs_semantics`)."""
    return needs_semantics(method) or bool(getattr(method, "uses_semantics", False))


def segment_with(
    method: Any,
    image: RangeImage,
    points: np.ndarray,
    ground: Ground | None,
    semantics: np.ndarray | None = None,
) -> np.ndarray:
    """``method.segment(image, points, ground)``, with ``semantics`` ((N,) raw class of every
    point of ``points``) handed over only to a method that needs them (:func:`needs_semantics`):
    the class-agnostic runs, where the ground truth's classes are there for such methods."""
    if needs_semantics(method):
        return method.segment(image, points, ground, semantics=semantics)
    return method.segment(image, points, ground)


def segment_semantic(method: Any, prep: Prepared, semantics: np.ndarray) -> np.ndarray:
    """A run with semantics (``--semantics``): ``method``'s labels of the thing-class points of
    :func:`prepare_semantic`, the classes handed over to every method that uses them
    (:func:`uses_semantics`); ``semantics``: (N_scan,) as :func:`scan_semantics` gives them."""
    if uses_semantics(method):
        classes = prepared_semantics(prep, semantics)
        return method.segment(prep.image, prep.points, None, semantics=classes)
    return method.segment(prep.image, prep.points, None)


def prepared_semantics(prep: Prepared, semantics: np.ndarray | None = None) -> np.ndarray | None:
    """(N,) raw class of every evaluated point: ``semantics`` ((N_scan,), as
    :func:`scan_semantics` gives them) at the evaluated points, or the ground truth's classes
    (``prep.labels``) when None; None without labels."""
    if semantics is not None:
        return semantics if prep.keep is None else semantics[prep.keep]
    if prep.labels is None:
        return None
    from flic_cli.semantics import oracle_semantics

    return oracle_semantics(prep.labels)


def cluster_ground(
    method: Any, points: np.ndarray, ground: Ground, semantics: np.ndarray | None = None
) -> np.ndarray:
    """``method``'s per-point labels after a ground step (``remover.extract``): on the image it
    leaves, without its ground and held cells (whose points take the cluster of the cell
    standing on them, ``ground.attached``)."""
    return segment_with(method, ground.image, points, ground, semantics)


@dataclass(frozen=True)
class Segmenter:
    """One method with its ground remover: ``segmenter(image, points) -> (labels, ground)``.

    Built once per run (:func:`build_segmenter`) and sent as it is to worker processes.

    Attributes
    ----------
    name : the method variant's name in the config (e.g. ``"flic14"``)
    kind : the method's kind (``"flic"``, ``"dbscan"``, ...)
    method : the clusterer (see :mod:`flic_cli.methods`)
    ground_name : the remover's name (``"paper"``, ...), None in the "No Ground" setting
    remover : the ground remover (see :mod:`flic_cli.ground`), None in the "No Ground" setting
    """

    name: str
    kind: str
    method: Any
    ground_name: str | None
    remover: Any

    def ground_step(self, image: RangeImage, points: np.ndarray) -> Ground | None:
        """The remover's decision as the clusterers take it
        (:meth:`flic_cli.ground.base.GroundRemover.extract`), or None when there is no
        remover."""
        return None if self.remover is None else self.remover.extract(image, points)

    def cluster(
        self,
        image: RangeImage,
        points: np.ndarray,
        ground: Ground | None,
        semantics: np.ndarray | None = None,
    ) -> np.ndarray:
        """The method's per-point labels given the ground step's result (or None);
        ``semantics``: (N,) raw class per point, for a method that needs them."""
        if ground is None:
            return segment_with(self.method, image, points, None, semantics)
        return cluster_ground(self.method, points, ground, semantics)

    def run(
        self, image: RangeImage, points: np.ndarray, semantics: np.ndarray | None = None
    ) -> tuple[np.ndarray, Ground | None]:
        """Per-point labels (0 = none or ground) and the ground step's result (or None)."""
        ground = self.ground_step(image, points)
        return self.cluster(image, points, ground, semantics), ground

    def __call__(
        self, image: RangeImage, points: np.ndarray, semantics: np.ndarray | None = None
    ) -> tuple[np.ndarray, Any]:
        """Per-point labels (0 = none or ground) and the ground mask used (or None)."""
        labels, ground = self.run(image, points, semantics)
        return labels, None if ground is None else ground.mask

    def with_param(self, value: float) -> Segmenter:
        """The same segmenter with the method's main parameter (sweeps) set to ``value``."""
        from flic_cli.component import describe

        param = self.method.main_param
        try:
            method = dataclasses.replace(self.method, **{param: value})
        except (TypeError, ValueError) as exc:
            raise FlicInputError(None, f"{param} = {value:g}: {describe(exc)}") from None
        return dataclasses.replace(self, method=method)


#: ``--ground-remover``: ``own`` picks each variant's ``ground`` key; any registered remover name
#: applies that remover to every method.
OWN = "own"


def build_segmenter(
    config: Config, name: str, setting: str, ground_remover: str = "paper"
) -> Segmenter:
    """Build the segmenter of method variant ``name``.

    Parameters
    ----------
    config : the loaded config.
    name : a ``[methods.NAME]`` variant.
    setting : ``"ground"`` or ``"no-ground"`` (no remover runs in the latter).
    ground_remover : a remover's name (``"paper"``: the paper's protocol applies the paper's
        extraction to every method) or ``"own"`` (each variant's own ``ground`` key).
    """
    spec = config.method(name)
    check_setting(setting)
    if spec.kind in registry.METHODS:
        registry.check_installed(f"method {name!r}", registry.METHODS[spec.kind])
    check_installed(spec.method)
    if setting == "no-ground":
        return Segmenter(name, spec.kind, spec.method, None, None)
    remover = spec.ground if ground_remover == OWN else ground_remover
    if remover in registry.REMOVERS:
        registry.check_installed(f"ground remover {remover!r}", registry.REMOVERS[remover])
    check_installed(config.remover(remover))
    return Segmenter(name, spec.kind, spec.method, remover, config.remover(remover))


def build_segmenters(
    config: Config, names: list[str], setting: str, ground_remover: str = "paper"
) -> list[Segmenter]:
    """:func:`build_segmenter` for every name."""
    return [build_segmenter(config, n, setting, ground_remover) for n in names]


def resolve_method(method: str, mc: int | None) -> str:
    """``--method flic --mc 14`` -> ``"flic14"``; other names pass through."""
    if mc is not None:
        if method != "flic":
            raise FlicInputError(None, "--mc applies to --method flic only")
        return f"flic{mc}"
    return "flic0" if method == "flic" else method


def parse_methods(text: str | None, config: Config, semantics: bool = False) -> list[str]:
    """Comma-separated method variant names, checked against the config (None: its defaults,
    and with ``semantics`` its ``default_semantic_methods`` after them)."""
    if text is None:
        names = [*config.default_methods, *(config.default_semantic_methods if semantics else ())]
        return list(dict.fromkeys(names))
    names = list(dict.fromkeys(t.strip() for t in text.split(",") if t.strip()))
    if not names:
        raise FlicInputError(None, f"--methods is empty (known: {', '.join(config.methods)})")
    for name in names:
        config.method(name)
    return names
