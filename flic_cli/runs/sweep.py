"""``flic sweep-threshold``: IoU_mu and P_mu against a method's main parameter (paper Fig. 8).

Each worker reads and prepares a frame once, extracts the ground once (ground setting), and runs
the method at every parameter value on the same range image; it returns the per-object IoUs of
every value. The parent pools them over all frames in frame order (so the result does not depend
on ``--jobs``), writes ``sweep.csv`` and ``sweep.png`` atomically.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

from flic_cli.errors import FlicInputError
from flic_cli.io.atomic import atomic_write
from flic_cli.io.base import FrameRef
from flic_cli.metrics import match_objects, summarize
from flic_cli.runs.evaluate import load_labelled_frame, percent, select_labelled
from flic_cli.runs.parallel import imap_frames
from flic_cli.runs.pipeline import SETTINGS, Segmenter, make_segmenter, prepare

#: Default sweep range ``(from, to, step)`` of each method kind's main parameter.
DEFAULT_RANGES: dict[str, tuple[float, float, float]] = {
    "flic": (0.2, 1.5, 0.05),
    "bogoslavskyi": (2.0, 30.0, 1.0),
    "dbscan": (0.2, 1.5, 0.1),
}

#: Axis labels of the main parameters.
PARAM_LABELS: dict[str, str] = {
    "threshold_m": "distance threshold [m]",
    "angle_deg": "angle threshold beta [deg]",
    "eps_m": "DBSCAN eps [m]",
}

#: Columns of ``sweep.csv`` (scores in percent).
SWEEP_COLUMNS: tuple[str, ...] = (
    "param",
    "value",
    "iou_mu",
    "p_mu",
    "p_0.50",
    "p_0.75",
    "p_0.95",
    "objects",
)

_MAX_VALUES = 10_000


def sweep_values(start: float, stop: float, step: float) -> np.ndarray:
    """``start, start + step, ..., stop`` (stop included when on the grid), rounded to 1e-6.

    Raises
    ------
    FlicInputError
        When ``step <= 0``, ``stop < start``, a value is not positive, or there are too many.
    """
    if not step > 0:
        raise FlicInputError(None, f"--step must be positive, got {step}")
    if stop < start:
        raise FlicInputError(None, f"--to ({stop}) must not be below --from ({start})")
    if start <= 0:
        raise FlicInputError(None, f"--from must be positive, got {start}")
    if (stop - start) / step > _MAX_VALUES:
        raise FlicInputError(None, f"more than {_MAX_VALUES} values: use a larger --step")
    return np.round(np.arange(start, stop + step / 2, step), 6)


def method_kind(cfg: dict[str, Any], name: str) -> str:
    """The ``kind`` of method variant ``name`` (``flic``, ``bogoslavskyi``, ``dbscan``)."""
    methods = cfg.get("methods", {})
    if name not in methods:
        raise FlicInputError(None, f"unknown method {name!r} (known: {', '.join(methods)})")
    return str(methods[name].get("kind"))


@dataclass
class SweepFrameResult:
    """Per-object IoUs of one frame at every value: ``ious[v]`` is an ``(M,)`` array."""

    sequence: str
    frame: int
    ious: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    error: tuple[str | None, str] | None = None


def sweep_frame(
    ref: FrameRef,
    cfg: dict[str, Any],
    method: str,
    setting: str,
    ground_remover: str,
    values: tuple[float, ...],
) -> SweepFrameResult:
    """Evaluate one method at every value of its main parameter on one frame.

    The frame is read and projected once, and (ground setting) its ground extracted once.

    Returns
    -------
    SweepFrameResult
        ``ious`` of shape ``(len(values), objects)``; input errors are returned, not raised.
    """
    try:
        frame = load_labelled_frame(ref)
        prep = prepare(frame, setting, cfg.get("projection", {}))
        base: Segmenter = make_segmenter(cfg, method, setting, ground_remover)
        ground = base.extract_ground(prep.image, prep.points)
        rows = []
        for value in values:
            labels = base.with_param(float(value)).method.segment(prep.image, prep.points, ground)
            rows.append(match_objects(prep.labels, labels).iou)
        ious = np.vstack(rows) if rows else np.zeros((0, 0))
        return SweepFrameResult(ref.sequence, ref.frame, ious)
    except FlicInputError as exc:
        return SweepFrameResult(
            ref.sequence, ref.frame, error=(None if exc.path is None else str(exc.path), exc.reason)
        )


@dataclass
class SweepResult:
    """What :func:`run_sweep` produced.

    Attributes
    ----------
    table : ``sweep.csv`` as a DataFrame.
    param : the swept parameter's name.
    best_value, best_iou_mu : the value with the highest IoU_mu (the lowest such value on ties)
        and that IoU_mu in percent.
    frames, skipped : frames evaluated, frames without labels left out.
    csv, png : the files written.
    """

    table: pd.DataFrame
    param: str
    best_value: float
    best_iou_mu: float
    frames: int
    skipped: int
    csv: Path
    png: Path

    def line(self) -> str:
        """One line summary."""
        return (
            f"best {self.param} = {self.best_value:g}: IoU_mu {self.best_iou_mu:.2f}% over "
            f"{int(self.table['objects'].iloc[0]) if len(self.table) else 0} objects in "
            f"{self.frames} frames -> {self.csv}, {self.png}"
        )


def run_sweep(
    data: Path,
    out: Path,
    method: str,
    cfg: dict[str, Any],
    start: float | None = None,
    stop: float | None = None,
    step: float | None = None,
    setting: str = "no-ground",
    sequences: list[str] | None = None,
    frames: tuple[int | None, int | None] | None = None,
    ground_remover: str = "paper",
    jobs: int = 1,
    scheduler: str | None = None,
    skip_missing: bool = False,
    progress: bool = True,
) -> SweepResult:
    """Sweep a method's main parameter and write ``sweep.csv`` and ``sweep.png`` into ``out``.

    Parameters
    ----------
    data : labelled SemanticKITTI root or sequence.
    out : output folder.
    method : method variant (``flic0``, ``bogoslavskyi``, ``dbscan``, ...).
    cfg : loaded config.
    start, stop, step : the values (defaults per method kind: :data:`DEFAULT_RANGES`).
    setting : ``"no-ground"`` (default: isolates the clusterer) or ``"ground"``.
    sequences, frames : selection.
    ground_remover : ground extraction of the ground setting (``"paper"`` or ``"own"``).
    jobs, scheduler : parallelism (see :func:`flic_cli.runs.parallel.imap_frames`).
    skip_missing : leave out frames without ``.label`` instead of failing.
    progress : show a progress bar.

    Returns
    -------
    SweepResult
    """
    if setting not in SETTINGS:
        raise FlicInputError(None, f"--setting must be one of {', '.join(SETTINGS)}")
    kind = method_kind(cfg, method)
    d_start, d_stop, d_step = DEFAULT_RANGES.get(kind, (None, None, None))
    start = d_start if start is None else start
    stop = d_stop if stop is None else stop
    step = d_step if step is None else step
    if start is None or stop is None or step is None:
        raise FlicInputError(
            None, f"method kind {kind!r} has no default range: give --from/--to/--step"
        )
    values = sweep_values(float(start), float(stop), float(step))
    base = make_segmenter(cfg, method, setting, ground_remover)
    param = base.method.main_param
    for value in values:  # fail on a bad value before any frame is read
        try:
            base.with_param(float(value))
        except (TypeError, ValueError) as exc:
            raise FlicInputError(None, f"{param} = {value:g}: {exc}") from None

    refs, skipped = select_labelled(data, sequences, frames, skip_missing)
    worker = functools.partial(
        sweep_frame,
        cfg=cfg,
        method=method,
        setting=setting,
        ground_remover=ground_remover,
        values=tuple(float(v) for v in values),
    )
    per_frame: dict[tuple[str, int], np.ndarray] = {}
    with tqdm(total=len(refs), desc=f"sweep {method}", unit="frame", disable=not progress) as bar:
        for result in imap_frames(worker, refs, jobs, scheduler):
            if result.error is not None:
                raise FlicInputError(result.error[0], result.error[1])
            per_frame[(result.sequence, result.frame)] = result.ious
            bar.update(1)

    ordered = [per_frame[(r.sequence, r.frame)] for r in refs]
    ious = np.hstack(ordered) if ordered else np.zeros((values.size, 0))
    rows = []
    for k, value in enumerate(values):
        s = summarize(ious[k])
        rows.append(
            {
                "param": param,
                "value": float(value),
                **{c: percent(s[c]) for c in SWEEP_COLUMNS[2:-1]},
                "objects": int(s["objects"]),
            }
        )
    table = pd.DataFrame(rows, columns=list(SWEEP_COLUMNS))
    raw = np.array([summarize(ious[k])["iou_mu"] for k in range(values.size)], dtype=float)
    best = int(np.nanargmax(raw)) if np.isfinite(raw).any() else 0

    out = Path(out)
    csv_path, png_path = out / "sweep.csv", out / "sweep.png"
    with atomic_write(csv_path) as tmp:
        table.to_csv(tmp, index=False)
    from flic_cli.plots import plot_sweep

    plot_sweep(
        table["value"].to_numpy(),
        table["iou_mu"].to_numpy(),
        table["p_mu"].to_numpy(),
        best,
        png_path,
        xlabel=PARAM_LABELS.get(param, param),
        title=f"{method}, {setting}: {len(refs)} frames, {int(table['objects'].iloc[0])} objects",
    )
    return SweepResult(
        table,
        param,
        float(values[best]),
        float(table["iou_mu"].iloc[best]),
        len(refs),
        skipped,
        csv_path,
        png_path,
    )
