"""``flic sweep-threshold``: IoU_mu and P_mu against a method's main parameter (paper Fig. 8).

Each worker reads and prepares a frame once, extracts the ground once (ground setting), and runs
the method at every parameter value on the same range image; it returns the per-object IoUs of
every value. The parent pools them over all frames in frame order (so the result does not depend
on ``--jobs``), writes ``sweep.csv`` and ``sweep.png`` atomically.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.errors import FlicInputError
from flic_cli.io.atomic import write_table
from flic_cli.io.base import Dataset, FrameRef
from flic_cli.metrics import match_objects, summarize
from flic_cli.projection import Projection
from flic_cli.runs.evaluate import select_labelled
from flic_cli.runs.frames import FrameLoop, Skipped, sort_skipped, write_skipped
from flic_cli.runs.output import check_output_dir, holding_out_lock
from flic_cli.runs.parallel import check_scheduler
from flic_cli.runs.pipeline import Segmenter, build_segmenter, prepare, prepared_semantics
from flic_cli.runs.scoring import load_labelled_frame
from flic_cli.runs.spec import SweepRun
from flic_cli.runs.tables import percent
from flic_cli.sensor_params import for_dataset

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
        When a bound is not finite (nan, inf), ``step <= 0``, ``stop < start``, a value is not
        positive, or there are too many.
    """
    for name, value in (("--from", start), ("--to", stop), ("--step", step)):
        if not np.isfinite(value):
            raise FlicInputError(None, f"{name} must be a finite number, got {value}")
    if not step > 0:
        raise FlicInputError(None, f"--step must be positive, got {step}")
    if stop < start:
        raise FlicInputError(None, f"--to ({stop}) must not be below --from ({start})")
    if start <= 0:
        raise FlicInputError(None, f"--from must be positive, got {start}")
    if (stop - start) / step > _MAX_VALUES:
        raise FlicInputError(None, f"more than {_MAX_VALUES} values: use a larger --step")
    return np.round(np.arange(start, stop + step / 2, step), 6)


@dataclass(frozen=True)
class SweepJob:
    """One method at every value of its main parameter on a frame (picklable, sent once).

    The frame is read and projected once, and (ground setting) its ground extracted once.
    Called on a frame, returns the per-object IoUs, shape ``(values, objects)``.
    """

    dataset: Dataset
    segmenters: tuple[Segmenter, ...]
    setting: str
    projection: Projection

    def __call__(self, ref: FrameRef) -> np.ndarray:
        prep = prepare(load_labelled_frame(self.dataset, ref), self.setting, self.projection)
        ground = self.segmenters[0].ground_step(prep.image, prep.points)
        classes = prepared_semantics(prep)  # the ground truth's, for methods that need them
        rows = [
            match_objects(prep.labels, s.cluster(prep.image, prep.points, ground, classes)).iou
            for s in self.segmenters
        ]
        return np.vstack(rows) if rows else np.zeros((0, 0))


@dataclass
class SweepResult:
    """What :func:`run_sweep` produced.

    Attributes
    ----------
    table : ``sweep.csv`` as a DataFrame.
    param : the swept parameter's name.
    best_value, best_iou_mu : the value with the highest IoU_mu (the lowest such value on ties)
        and that IoU_mu in percent.
    frames, missing : frames evaluated, frames without labels left out (``--skip-missing``).
    csv, png : the files written.
    skipped : bad frames left out (``--skip-bad``, listed in ``skipped.csv``).
    """

    table: pd.DataFrame
    param: str
    best_value: float
    best_iou_mu: float
    frames: int
    missing: int
    csv: Path
    png: Path
    skipped: list[Skipped]

    def line(self) -> str:
        """One line summary."""
        return (
            f"best {self.param} = {self.best_value:g}: IoU_mu {self.best_iou_mu:.2f}% over "
            f"{int(self.table['objects'].iloc[0]) if len(self.table) else 0} objects in "
            f"{self.frames} frames -> {self.csv}, {self.png}"
        )


@holding_out_lock
def run_sweep(spec: SweepRun) -> SweepResult:
    """Sweep a method's main parameter and write ``sweep.csv`` and ``sweep.png`` into
    ``spec.out``.

    Parameters
    ----------
    spec : what to sweep and how (:class:`flic_cli.runs.spec.SweepRun`; the selection's setting
        defaults to ``"no-ground"``, which isolates the clusterer, its ground remover to
        ``"paper"``; the values default to the method class's ``sweep_range``).
    """
    sel = spec.selection
    config = sel.loaded_config()
    setting = sel.setting_or("no-ground")
    check_scheduler(spec.scheduler)
    method, start, stop, step = spec.method, spec.start, spec.stop, spec.step
    base = build_segmenter(config, method, setting, sel.remover_or("paper"))
    d_start, d_stop, d_step = getattr(base.method, "sweep_range", (None, None, None))
    start = d_start if start is None else start
    stop = d_stop if stop is None else stop
    step = d_step if step is None else step
    if start is None or stop is None or step is None:
        raise FlicInputError(
            None,
            f"method kind {base.kind!r} declares no sweep_range: give --from/--to/--step",
        )
    values = sweep_values(float(start), float(stop), float(step))
    param = base.method.main_param
    # every value is validated here, before any frame is read
    segmenters = tuple(base.with_param(float(v)) for v in values)
    ds, refs, missing = select_labelled(sel.data, sel.sequences, sel.frames, spec.skip_missing)
    derived = for_dataset(config, ds, refs)  # the sensor's derived parameters
    if derived is not config:
        config = derived
        base = build_segmenter(config, method, setting, sel.remover_or("paper"))
        segmenters = tuple(base.with_param(float(v)) for v in values)
    job = SweepJob(ds, segmenters, setting, config.projection)
    out = check_output_dir(Path(spec.out), ds.folders())

    per_frame: dict[tuple[str, int], np.ndarray] = {}
    loop = FrameLoop(
        job, refs, sel.jobs, spec.scheduler, sel.skip_bad, f"sweep {method}", sel.progress
    )
    for ref, ious in loop:
        per_frame[(ref.sequence, ref.frame)] = ious
    if loop.skipped and not per_frame:
        write_skipped(out / "skipped.csv", sort_skipped(loop.skipped))
        raise FlicInputError(
            sel.data,
            f"every selected frame is bad ({len(loop.skipped)}, listed in "
            f"{out / 'skipped.csv'}): nothing to sweep",
        )

    ordered = [per_frame[k] for k in ((r.sequence, r.frame) for r in refs) if k in per_frame]
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

    csv_path, png_path = out / "sweep.csv", out / "sweep.png"
    write_table(csv_path, table)
    from flic_cli.plots import plot_sweep

    plot_sweep(
        table["value"].to_numpy(),
        table["iou_mu"].to_numpy(),
        table["p_mu"].to_numpy(),
        best,
        png_path,
        xlabel=getattr(base.method, "sweep_label", param),
        title=f"{method}, {setting}: {len(per_frame)} frames, "
        f"{int(table['objects'].iloc[0])} objects",
    )
    if loop.skipped:
        write_skipped(out / "skipped.csv", sort_skipped(loop.skipped))
    return SweepResult(
        table,
        param,
        float(values[best]),
        float(table["iou_mu"].iloc[best]),
        len(per_frame),
        missing,
        csv_path,
        png_path,
        sort_skipped(loop.skipped),
    )
