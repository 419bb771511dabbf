"""flic from Python: numpy arrays in, cluster labels out.

The same chain as the command line (projection -> ground extraction -> clusterer), configured the
same way (a method variant's name, e.g. ``"flic14"``, and optionally a ``--config``-style file).

Example
-------
>>> import flic_cli.api as flic
>>> frame = flic.load_frame(flic.sample_data(), frame=0)      # the built-in synthetic sample
>>> labels = flic.segment_points(frame.points, method="flic14")
>>> labels.shape == (frame.points.shape[0],) and int(labels.max()) > 10
True
>>> image = flic.segment_range_image(ranges, elevation)        # doctest: +SKIP

Whole runs, as the commands do them, take one run specification (:mod:`flic_cli.runs.spec`):

>>> sel = flic.Selection(flic.sample_data(), frames=(0, 2))              # doctest: +SKIP
>>> flic.run(flic.EvaluateRun(sel, Path("eval"), ["flic0", "flic14"])).table  # doctest: +SKIP
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from flic_cli.config import Config, load_config
from flic_cli.io.base import Frame, FrameRef
from flic_cli.range_image import RangeImage, from_sensor_image
from flic_cli.runs.pipeline import OWN, Segmenter, build_segmenter, prepare
from flic_cli.runs.spec import BenchmarkRun, EvaluateRun, SegmentRun, Selection, SweepRun

__all__ = [
    "BenchmarkRun",
    "EvaluateRun",
    "SegmentRun",
    "Selection",
    "SweepRun",
    "load_frame",
    "methods",
    "run",
    "sample_data",
    "segment_frame",
    "segment_points",
    "segment_range_image",
]


def _config(config: Config | str | Path | None) -> Config:
    return config if isinstance(config, Config) else load_config(config)


def _segmenter(
    cfg: Config, method: str, ground: str | None, image: RangeImage | None = None
) -> Segmenter:
    """The method with its ground remover (none when ``ground`` is None), with the parameters
    that follow the sensor derived from ``image``'s rows and columns
    (:func:`flic_cli.sensor_params.for_beams`) unless the config sets them."""
    if image is not None:
        from flic_cli.sensor_params import BeamTable, for_beams

        cfg = for_beams(cfg, BeamTable.of_image(image))[0]
    if ground is None:
        return build_segmenter(cfg, method, "no-ground")  # the "no-ground" segmenter has none
    return build_segmenter(cfg, method, "ground", ground)


def methods(config: Config | str | Path | None = None) -> list[str]:
    """The method variants that ``method=`` accepts (the presets, plus those of ``config``)."""
    return list(_config(config).methods)


def sample_data() -> Path:
    """The built-in synthetic sample's SemanticKITTI root (written once to a cache folder)."""
    from flic_cli.sample import ensure_sample

    return ensure_sample().kitti_root


def run(spec: SegmentRun | EvaluateRun | BenchmarkRun | SweepRun) -> Any:
    """Run a whole command on a dataset, as ``flic segment`` / ``evaluate`` / ``benchmark`` /
    ``sweep-threshold`` do (outputs written to ``spec.out``).

    Returns
    -------
    What the run returns: a :class:`flic_cli.runs.segment.SegmentSummary`,
    :class:`flic_cli.runs.evaluate.EvaluateResult`,
    :class:`flic_cli.runs.benchmark.BenchmarkResult` or :class:`flic_cli.runs.sweep.SweepResult`.
    """
    if isinstance(spec, SegmentRun):
        from flic_cli.runs.segment import run_segment

        return run_segment(spec)
    if isinstance(spec, EvaluateRun):
        from flic_cli.runs.evaluate import run_evaluate

        return run_evaluate(spec)
    if isinstance(spec, BenchmarkRun):
        from flic_cli.runs.benchmark import run_benchmark

        return run_benchmark(spec)
    if isinstance(spec, SweepRun):
        from flic_cli.runs.sweep import run_sweep

        return run_sweep(spec)
    raise TypeError(f"not a run specification: {type(spec).__name__}")


def load_frame(
    data: str | Path,
    frame: int = 0,
    sequence: str | None = None,
    reader: dict[str, object] | None = None,
) -> Frame:
    """Load one frame of a dataset (SemanticKITTI or a Moosmann log).

    Parameters
    ----------
    data : a SemanticKITTI root or sequence folder, or a Moosmann log.
    frame : the frame number.
    sequence : the sequence (or log) name; default: the first that has the frame.
    reader : reader options, e.g. ``{"columns": 1800, "rows": 16}`` for a PCD without ring
        field (see :func:`flic_cli.io.open_dataset`).

    Returns
    -------
    Frame
        ``points`` (N, 3) metres in scan order, ``labels`` (N,) uint32 or None, and for a
        Moosmann log its range image ``image``.
    """
    from flic_cli.io import open_dataset

    ds = open_dataset(
        data, None if sequence is None else [sequence], (frame, frame + 1), reader=reader
    )
    return ds.load(ds.refs()[0])


def segment_points(
    points: np.ndarray,
    method: str = "flic14",
    *,
    ground: str | None = OWN,
    scan_order: bool = True,
    config: Config | str | Path | None = None,
) -> np.ndarray:
    """Cluster a lidar scan given as points.

    Parameters
    ----------
    points : (N, 3) or (N, 4) array, metres, sensor frame (x forward, y left, z up); extra
        columns are ignored. Points with NaN/inf coordinates get label 0.
    method : a method variant (:func:`methods`), e.g. ``"flic0"``, ``"flic14"``, ``"dbscan"``.
    ground : the ground remover: ``"own"`` (the variant's own), a remover's name (``"paper"``,
        ...), or None to cluster every point.
    scan_order : the points come in the sensor's scan order, ring after ring (KITTI's order):
        the image rows are recovered from it. False: a spherical projection (``[projection]``
        field of view of the config) is used instead.
    config : a config file (``--config`` layout) or a loaded :class:`flic_cli.config.Config`.

    Returns
    -------
    (N,) int32 cluster id of every point, 0 = unclustered or ground.
    """
    import dataclasses

    cfg = _config(config)
    pts = np.asarray(points, dtype=np.float32)
    if pts.ndim != 2 or pts.shape[1] < 3:
        raise ValueError(f"points must have shape (N, 3) or (N, 4), got {pts.shape}")
    finite = np.isfinite(pts[:, :3]).all(axis=1)
    ref = FrameRef("array", 0, Path("<array>"), None, "array")
    frame = Frame(
        ref,
        np.ascontiguousarray(pts[finite, :3]),
        None,
        finite=None if finite.all() else finite,
    )
    projection = cfg.projection
    if not scan_order:
        projection = dataclasses.replace(projection, mode="spherical")
    prep = prepare(frame, "ground", projection)
    labels, _ = _segmenter(cfg, method, ground, prep.image)(prep.image, prep.points)
    return prep.scan_labels(labels).astype(np.int32, copy=False)


def segment_frame(
    frame: Frame,
    method: str = "flic14",
    *,
    ground: str | None = OWN,
    config: Config | str | Path | None = None,
) -> np.ndarray:
    """Cluster a frame of :func:`load_frame`, on its sensor's own range image when it has one
    (Ouster, Velodyne, PCD with rings, nuScenes, Moosmann), else projected as the config says.

    Parameters
    ----------
    frame : a loaded frame.
    method, ground, config : as for :func:`segment_points`.

    Returns
    -------
    (N_stored,) int32 cluster id of every point of the frame as stored (0 = unclustered, ground,
    or a point the reader left out).
    """
    cfg = _config(config)
    prep = prepare(frame, "ground", cfg.projection)
    labels, _ = _segmenter(cfg, method, ground, prep.image)(prep.image, prep.points)
    return prep.scan_labels(labels).astype(np.int32, copy=False)


def segment_range_image(
    ranges: np.ndarray,
    elevation: np.ndarray,
    method: str = "flic14",
    *,
    ground: str | None = OWN,
    config: Config | str | Path | None = None,
) -> np.ndarray:
    """Cluster a range image (a sensor's own image, e.g. a Moosmann log's).

    Parameters
    ----------
    ranges : (H, W) ranges in metres, 0 = no measurement. Row 0 is the top beam; column 0 looks
        backwards (azimuth +180 deg) and the azimuth decreases to -180 deg at the last column.
    elevation : (H,) elevation of every row, radians, positive up.
    method, ground, config : as for :func:`segment_points`.

    Returns
    -------
    (H, W) int32 cluster id of every pixel, 0 = none.
    """
    cfg = _config(config)
    image = from_sensor_image(np.asarray(ranges, dtype=np.float32), np.asarray(elevation))
    ref = FrameRef("array", 0, Path("<array>"), None, "array")
    frame = Frame(ref, image.to_points()[image.point_pixel], None, image)
    prep = prepare(frame, "ground", cfg.projection)
    labels, _ = _segmenter(cfg, method, ground, prep.image)(prep.image, prep.points)
    out = np.zeros(image.ranges.size, dtype=np.int32)
    out[image.point_pixel] = labels
    return out.reshape(image.ranges.shape)
