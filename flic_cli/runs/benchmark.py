"""``flic benchmark``: per-frame runtime of every method, as in the paper's section IV-A.

Procedure
---------
1. Warm-up, on the first frame that loads: every method runs ``warmup`` times, so that JIT
   compilation (or loading the compiled kernels from numba's on-disk cache) and first-use imports
   are not timed. The first call's time is recorded separately ("first call incl. JIT/cache
   load").
2. Timing, one pass over the frames per method: every frame is read and projected to its range
   image, then the method segments it (``segmenter(image, points)``: range image in, labels out,
   ground extraction included) and only that call is timed. Reading (stage ``read``) and the
   projection (stage ``project``) are timed in a pass of their own. Every method thus runs as it
   would in a pipeline, right after its frame was read, and no method runs in the caches and
   the allocator state that another left behind (with the methods interleaved per frame, the
   frames after each DBSCAN frame were up to a third slower: Bogoslavskyi 0.270 against
   0.204 ms per 870 x 64 frame).
   The garbage collector is disabled during each timed call. ``--repeat R`` times each call R
   times and keeps the median.
3. Methods declared slow (``slow = True`` on the class: DBSCAN, seconds per frame) run only on
   frames whose position in the selection is a multiple of ``slow_every``.
4. ``--rounds N`` makes N rounds of these passes, the order of the passes turned by one each
   round, and keeps each frame's median over the rounds. On a shared machine, other work slows
   every call that runs at the same moment (back-to-back repeats included), which shows up as
   per-frame spikes that are not the method's; passes minutes apart do not meet the same
   disturbance, so the median over rounds leaves what depends on the frame itself.
   ``frames.csv`` holds those medians; ``environment.json`` records the rounds.

Everything runs single-threaded unless ``threads`` says otherwise (numba and the native thread
pools are limited, see :mod:`flic_cli.runs.environment`).

Outputs (all written atomically)
--------------------------------
``frames.csv``
    One row per (method or stage, timed frame): ``method, index, sequence, frame, milliseconds,
    points, clusters``. ``index`` is the frame's position in the selection; stages ``read`` and
    ``project`` have no ``clusters``.
``summary.csv``
    One row per method and stage: ``method, kind, frames, median_ms, mean_ms, p5_ms, p95_ms,
    p99_ms, max_ms, hz_median, hz_mean, stability, points_median, clusters_median`` and
    ``speedup_vs_<other>`` for every method. ``stability`` = p99 / median. ``speedup_vs_Y`` of
    method X = median(Y) / median(X) **over the frames both were timed on** (> 1: X is faster), so
    that DBSCAN, timed on every n-th frame only, is compared with the others on the same frames;
    between methods timed on every frame it is the ratio of the medians of this table.
``histogram.csv``
    ``method, bin_lo_ms, bin_hi_ms, count``: the same :data:`HIST_EDGES_MS` for every method
    (10 log-spaced bins per decade from 0.01 ms to 100 s; times outside fall into the first or
    last bin, so the counts of a method sum to its ``frames``).
``environment.json``
    CPU, cores, Python and library versions, threads in effect, command line, date, the run's
    parameters and the warm-up (first-call) times.
``latency.csv`` (recordings: bags, pcaps)
    Per method and revolution, decode + range image + ground + cluster in recording order, each
    stage timed (:mod:`flic_cli.runs.latency`); the report says whether the p99 keeps up with
    10 / 20 Hz.
``runtime.png``, ``boxplot_hz.png``, ``histogram.png``
    Per-frame runtime over the log on a log scale (paper Fig. 9), box plot of the per-frame rate
    in Hz (Fig. 10), runtime histograms.
"""

from __future__ import annotations

import gc
import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from flic_cli.errors import FlicInputError
from flic_cli.io import open_dataset
from flic_cli.io.atomic import atomic_write, write_table
from flic_cli.io.base import FrameRef
from flic_cli.projection import Projection
from flic_cli.runs import latency
from flic_cli.runs.environment import collect_environment, environment_line, thread_limits
from flic_cli.runs.frames import FrameLoop, sort_skipped, write_skipped
from flic_cli.runs.output import check_output_dir, holding_out_lock
from flic_cli.runs.pipeline import (
    Segmenter,
    build_segmenters,
    needs_semantics,
    prepare,
    prepared_semantics,
)
from flic_cli.runs.spec import BenchmarkRun
from flic_cli.sensor_params import for_dataset

#: Speed-ups measured on fewer frames than this are printed as an indication only.
FEW_FRAMES = 30

#: The stages timed besides the methods (file reading, projection to the range image).
STAGES = ("read", "project")

#: Histogram bin edges in milliseconds: 10 log-spaced bins per decade, 0.01 ms to 100 s.
HIST_EDGES_MS: np.ndarray = np.logspace(-2, 5, 71)

FRAME_COLUMNS = ["method", "index", "sequence", "frame", "milliseconds", "points", "clusters"]
STAT_COLUMNS = [
    "method",
    "kind",
    "frames",
    "median_ms",
    "mean_ms",
    "p5_ms",
    "p95_ms",
    "p99_ms",
    "max_ms",
    "hz_median",
    "hz_mean",
    "stability",
    "points_median",
    "clusters_median",
]
PRINT_COLUMNS = [
    "method",
    "frames",
    "median_ms",
    "mean_ms",
    "p95_ms",
    "p99_ms",
    "max_ms",
    "hz_median",
    "hz_mean",
    "stability",
]


@dataclass
class BenchmarkResult:
    """What :func:`run_benchmark` measured and wrote.

    Attributes
    ----------
    frames : the ``frames.csv`` table
    summary : the ``summary.csv`` table
    histogram : the ``histogram.csv`` table
    environment : the ``environment.json`` record
    out : the output folder
    files : the files written
    notes : lines worth printing (sub-sampled methods, skipped frames)
    """

    frames: pd.DataFrame
    summary: pd.DataFrame
    histogram: pd.DataFrame
    environment: dict[str, Any]
    out: Path
    files: list[Path] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def _speedups(self, methods: list[str]) -> list[str]:
        """The speed-up matrix; ratios over fewer than :data:`FEW_FRAMES` common frames get two
        significant figures and a ``~``, with their frame counts below."""
        by_method = self.summary.set_index("method")
        n = self.frames[self.frames["method"].isin(methods)].groupby("method")["index"].nunique()
        few = {m for m in methods if n.get(m, 0) < FEW_FRAMES}
        cells = {}
        for a in methods:
            cells[a] = {}
            for b in methods:
                value = by_method.loc[a, f"speedup_vs_{b}"]
                if not np.isfinite(value):
                    cells[a][b] = "-"
                elif a in few or b in few:
                    cells[a][b] = "~" + _significant(value, 2)
                else:
                    cells[a][b] = _significant(value, 3)
        table = pd.DataFrame(cells).T.loc[methods, methods]
        lines = [
            "speed-up (row vs column: column's median / row's median, on the frames both were "
            "timed on):",
            table.to_string(),
        ]
        if few:
            counts = ", ".join(f"{m} n = {int(n.get(m, 0))}" for m in methods if m in few)
            lines.append(f"~: fewer than {FEW_FRAMES} frames timed ({counts}), an indication only")
        return lines

    def report(self) -> str:
        """The lines ``flic benchmark`` prints: environment, warm-up, notes, summary, files."""
        env = self.environment
        first = env.get("warmup", {}).get("first_call_ms") or {}
        lines = [f"environment: {environment_line(env)}"]
        if first:
            lines.append(
                "first call incl. JIT/cache load (not in the statistics): "
                + ", ".join(f"{k} {v:.1f} ms" for k, v in first.items())
            )
        lines += self.notes
        table = self.summary[PRINT_COLUMNS].copy()
        lines.append(
            table.to_string(
                index=False,
                float_format=lambda x: f"{x:.3g}" if abs(x) < 100 else f"{x:.1f}",
            )
        )
        methods = self.summary.loc[self.summary["kind"] == "method", "method"].tolist()
        if len(methods) > 1:
            lines += self._speedups(methods)
        lines.append(f"wrote {', '.join(p.name for p in self.files)} -> {self.out}")
        return "\n".join(lines)


def _median_over_rounds(table: pd.DataFrame) -> pd.DataFrame:
    """One row per method (or stage) and frame: the median time over the rounds."""
    keys = ["method", "index", "sequence", "frame"]
    return table.groupby(keys, sort=False, as_index=False).agg(
        milliseconds=("milliseconds", "median"),
        points=("points", "first"),
        clusters=("clusters", "first"),
    )[FRAME_COLUMNS]


def _significant(value: float, digits: int) -> str:
    """``value`` rounded to ``digits`` significant figures, without an exponent (454, 0.0071)."""
    return np.format_float_positional(value, precision=digits, fractional=False, trim="-")


def _timed(func: Callable[[], Any], repeat: int) -> tuple[Any, int]:
    """Run ``func`` ``repeat`` times with the garbage collector off; (last result, median ns)."""
    times = []
    result = None
    for _ in range(repeat):
        enabled = gc.isenabled()
        gc.disable()
        try:
            t0 = time.perf_counter_ns()
            result = func()
            t1 = time.perf_counter_ns()
        finally:
            if enabled:
                gc.enable()
        times.append(t1 - t0)
    return result, int(np.median(times))


def _stats(ms: np.ndarray) -> dict[str, float]:
    median, mean = float(np.median(ms)), float(np.mean(ms))
    p5, p95, p99 = (float(v) for v in np.percentile(ms, [5, 95, 99]))
    return {
        "median_ms": median,
        "mean_ms": mean,
        "p5_ms": p5,
        "p95_ms": p95,
        "p99_ms": p99,
        "max_ms": float(np.max(ms)),
        "hz_median": 1000.0 / median if median > 0 else np.inf,
        "hz_mean": 1000.0 / mean if mean > 0 else np.inf,
        "stability": p99 / median if median > 0 else np.nan,
    }


def summarize(frames: pd.DataFrame, methods: list[str]) -> pd.DataFrame:
    """The ``summary.csv`` table of a ``frames.csv`` table.

    Parameters
    ----------
    frames : per-frame timings (:data:`FRAME_COLUMNS`).
    methods : the methods, in order (the other values of ``method`` are stages).
    """
    rows = []
    series = {m: frames[frames["method"] == m].set_index("index")["milliseconds"] for m in methods}
    names = list(methods) + [s for s in STAGES if (frames["method"] == s).any()]
    for name in names:
        sub = frames[frames["method"] == name]
        if sub.empty:
            continue
        row: dict[str, Any] = {
            "method": name,
            "kind": "method" if name in methods else "stage",
            "frames": len(sub),
            **_stats(sub["milliseconds"].to_numpy(dtype=np.float64)),
            "points_median": float(np.median(sub["points"])),
            "clusters_median": float(np.median(sub["clusters"].to_numpy(dtype=np.float64)))
            if name in methods
            else np.nan,
        }
        for other in methods:
            if name not in methods:
                row[f"speedup_vs_{other}"] = np.nan
                continue
            mine, theirs = series[name], series[other]
            common = mine.index.intersection(theirs.index)
            if common.empty:
                row[f"speedup_vs_{other}"] = np.nan
                continue
            row[f"speedup_vs_{other}"] = float(
                np.median(theirs.loc[common]) / np.median(mine.loc[common])
            )
        rows.append(row)
    return pd.DataFrame(rows, columns=STAT_COLUMNS + [f"speedup_vs_{m}" for m in methods])


def histogram(frames: pd.DataFrame, names: list[str]) -> pd.DataFrame:
    """The ``histogram.csv`` table: counts per :data:`HIST_EDGES_MS` bin, per method or stage."""
    edges = HIST_EDGES_MS
    parts = []
    for name in names:
        ms = frames.loc[frames["method"] == name, "milliseconds"].to_numpy(dtype=np.float64)
        if ms.size == 0:
            continue
        counts, _ = np.histogram(np.clip(ms, edges[0], edges[-1]), bins=edges)
        parts.append(
            pd.DataFrame(
                {"method": name, "bin_lo_ms": edges[:-1], "bin_hi_ms": edges[1:], "count": counts}
            )
        )
    return pd.concat(parts, ignore_index=True)


def _write_json(obj: dict[str, Any], path: Path) -> None:
    with atomic_write(path) as tmp:
        tmp.write_text(json.dumps(obj, indent=2, default=str) + "\n", encoding="utf-8")


def _plots(frames: pd.DataFrame, methods: list[str], out: Path, title: str) -> list[Path]:
    from flic_cli.plots import plot_hz_boxplot, plot_runtime_histogram, plot_runtime_series

    series, hz, counts = {}, {}, {}
    for m in methods:
        sub = frames[frames["method"] == m]
        ms = sub["milliseconds"].to_numpy(dtype=np.float64)
        series[m] = (sub["index"].to_numpy(), ms)
        hz[m] = 1000.0 / np.maximum(ms, 1e-9)
        counts[m] = np.histogram(np.clip(ms, HIST_EDGES_MS[0], HIST_EDGES_MS[-1]), HIST_EDGES_MS)[0]
    paths = [out / "runtime.png", out / "boxplot_hz.png", out / "histogram.png"]
    plot_runtime_series(series, paths[0], title=f"per-frame runtime, {title}")
    plot_hz_boxplot(hz, paths[1], title=f"frame rate, {title}")
    plot_runtime_histogram(counts, HIST_EDGES_MS, paths[2], title=f"runtime histogram, {title}")
    return paths


class BenchJob:
    """Times one frame: reading and projection when ``segmenter`` is None, else the segmenter
    alone (in this process only).

    On the first frame that loads, the segmenter first runs ``warmup`` untimed times (JIT
    compilation or numba's on-disk cache load, first-use imports); the first call's time is kept
    apart. :func:`run_benchmark` gives every method a job (and a pass over the frames) of its own.
    Returns the frame's rows of ``frames.csv``.
    """

    def __init__(
        self,
        dataset: Any,
        segmenter: Segmenter | None,
        setting: str,
        projection: Projection,
        index: dict[FrameRef, int],
        warmup: int,
        repeat: int,
    ) -> None:
        self.dataset = dataset
        self.segmenter = segmenter
        self.setting = setting
        self.projection = projection
        self.index = index
        self.warmup = warmup
        self.repeat = repeat
        self.first_call: dict[str, float] = {}
        self.warm_ms: dict[str, float] = {}
        self.warm_frame: dict[str, Any] | None = None

    def _warm_up(self, ref: FrameRef) -> None:
        t0 = time.perf_counter_ns()
        frame = self.dataset.load(ref)
        t1 = time.perf_counter_ns()
        prep = prepare(frame, self.setting, self.projection)
        t2 = time.perf_counter_ns()
        self.first_call = {"read": (t1 - t0) / 1e6, "project": (t2 - t1) / 1e6}
        seg = self.segmenter
        if seg is not None:
            classes = prepared_semantics(prep) if needs_semantics(seg.method) else None
            for k in range(self.warmup):
                _, ns = _timed(lambda: seg(prep.image, prep.points, classes), 1)
                if k == 0:
                    self.first_call[seg.name] = ns / 1e6
                self.warm_ms[seg.name] = ns / 1e6
        self.warm_frame = {"sequence": ref.sequence, "frame": ref.frame}

    def __call__(self, ref: FrameRef) -> list[tuple]:
        if self.warm_frame is None and self.warmup > 0:
            self._warm_up(ref)
        index = self.index[ref]
        seg = self.segmenter
        if seg is not None:  # the frame as a pipeline has it, then only the method is timed
            prep = prepare(self.dataset.load(ref), self.setting, self.projection)
            # a method that clusters per class gets the ground truth's classes, outside the timing
            classes = prepared_semantics(prep) if needs_semantics(seg.method) else None
            (labels, _), ns = _timed(lambda: seg(prep.image, prep.points, classes), self.repeat)
            n, clusters = int(prep.points.shape[0]), int(labels.max(initial=0))
            return [(seg.name, index, ref.sequence, ref.frame, ns / 1e6, n, clusters)]
        frame, ns_read = _timed(lambda: self.dataset.load(ref), 1)
        prep, ns_proj = _timed(lambda: prepare(frame, self.setting, self.projection), self.repeat)
        n = int(prep.points.shape[0])
        return [
            ("read", index, ref.sequence, ref.frame, ns_read / 1e6, prep.n_scan, -1),
            ("project", index, ref.sequence, ref.frame, ns_proj / 1e6, n, -1),
        ]


@holding_out_lock
def run_benchmark(spec: BenchmarkRun) -> BenchmarkResult:
    """Time every method on every selected frame and write the tables, plots and environment.

    Parameters
    ----------
    spec : what to time and how (:class:`flic_cli.runs.spec.BenchmarkRun`; the selection's
        setting defaults to ``"ground"``, ground extraction timed as part of every method, its
        ground remover to ``"own"``; ``jobs`` is not used, timing runs in one process).

    Returns
    -------
    BenchmarkResult
    """
    sel = spec.selection
    data, out, methods, config = sel.data, spec.out, spec.methods, sel.loaded_config()
    setting, ground_remover = sel.setting_or("ground"), sel.remover_or("own")
    warmup, repeat, rounds, slow_every = spec.warmup, spec.repeat, spec.rounds, spec.slow_every
    threads, plots, progress, skip_bad = spec.threads, spec.plots, sel.progress, sel.skip_bad
    if warmup < 0 or repeat < 1 or rounds < 1 or slow_every < 1 or threads < 1:
        raise FlicInputError(
            None, "--warmup must be >= 0, --repeat, --rounds, --slow-every and --threads >= 1"
        )
    clash = [m for m in methods if m in STAGES]
    if clash:
        raise FlicInputError(None, f"method name {clash[0]!r} is reserved for a timed stage")
    methods = list(dict.fromkeys(methods))
    ds = open_dataset(
        data, sel.sequences, sel.frames, require_labels=setting == "no-ground", reader=sel.reader
    )
    refs = ds.refs()
    out = check_output_dir(Path(out), ds.folders())
    config = for_dataset(config, ds, refs)  # the sensor's derived parameters
    segs = build_segmenters(config, methods, setting, ground_remover)
    index = {r: k for k, r in enumerate(refs)}
    every = {s.name: slow_every if getattr(s.method, "slow", False) else 1 for s in segs}

    # one job per method, and one (None) for reading and projection: each has a pass of its own
    jobs = {
        name: BenchJob(ds, seg, setting, config.projection, index, warmup, repeat)
        for name, seg in [(None, None), *((s.name, s) for s in segs)]
    }
    names = list(jobs)
    rows: list[tuple] = []
    with thread_limits(threads) as thread_info:
        for r in range(rounds):
            # the order of the passes turns by one every round (slow drifts meet each in turn)
            for name in names[r % len(names) :] + names[: r % len(names)]:
                what = "read + project" if name is None else name
                desc = f"benchmark {what}" + (f", round {r + 1}/{rounds}" if rounds > 1 else "")
                step = 1 if name is None else every[name]
                selected = [ref for ref in refs if index[ref] % step == 0]
                loop = FrameLoop(
                    jobs[name], selected, skip_bad=skip_bad, desc=desc, progress=progress
                )
                rows += [row for _, frame_rows in loop for row in frame_rows]
    first_call: dict[str, float] = {}  # the stages' first call is the first job's (imports)
    warm_ms: dict[str, float] = {}
    for j in jobs.values():
        for k, v in j.first_call.items():
            first_call.setdefault(k, v)
        warm_ms |= j.warm_ms
    warm_frame = next((j.warm_frame for j in jobs.values() if j.warm_frame), None)
    if not rows:
        raise FlicInputError(data, "no frame could be read")
    table = _median_over_rounds(pd.DataFrame(rows, columns=FRAME_COLUMNS))
    table["clusters"] = table["clusters"].astype("Int64").mask(table["clusters"] < 0)
    order = {name: k for k, name in enumerate([*methods, *STAGES])}
    table = table.sort_values(
        ["method", "index"], key=lambda c: c.map(order) if c.name == "method" else c, kind="stable"
    ).reset_index(drop=True)
    summary = summarize(table, methods)
    hist = histogram(table, [*methods, *STAGES])
    timed_frames = int(table.loc[table["method"] == "read", "index"].nunique())

    notes = []
    for m in methods:
        if every[m] > 1:
            n = int((table["method"] == m).sum())
            notes.append(
                f"{m}: timed only on frames with index % {every[m]} == 0 ({n} of {timed_frames} "
                f"frames, --slow-every {every[m]}); its speed-ups are computed on those frames"
            )
    if thread_info["numba"] != threads:
        notes.append(
            f"numba runs {thread_info['numba']} thread(s), not {threads}: NUMBA_NUM_THREADS was "
            f"{thread_info['numba_max']} when numba was imported"
        )
    if loop.skipped:
        notes.append(loop.note() or "")
    if warmup == 0:
        notes.append("no warm-up (--warmup 0): the first frame's times include compilation")

    env = collect_environment(
        thread_info,
        timer="time.perf_counter_ns",
        gc_disabled_while_timing=True,
        data=str(data),
        format=getattr(ds, "format", None),
        setting=setting,
        ground_remover=ground_remover,
        methods={s.name: {"kind": s.kind, "ground": s.ground_name} for s in segs},
        frames_selected=len(refs),
        frames_timed=timed_frames,
        repeat=repeat,
        rounds=rounds,
        slow_every=slow_every,
        subsampled={m: every[m] for m in methods if every[m] > 1},
        skipped_frames=[s.line() for s in sort_skipped(loop.skipped)],
        warmup={
            "runs": warmup,
            "frame": warm_frame,
            "first_call_ms": first_call,
            "last_warmup_ms": warm_ms,
            "note": "first call incl. JIT compilation / on-disk cache load; not in the statistics",
        },
    )

    files = [out / n for n in ("frames.csv", "summary.csv", "histogram.csv", "environment.json")]
    if loop.skipped:
        files.append(write_skipped(out / "skipped.csv", sort_skipped(loop.skipped)))
    write_table(files[0], table)
    write_table(files[1], summary)
    write_table(files[2], hist)
    _write_json(env, files[3])
    if getattr(ds, "format", None) in latency.STREAMS:  # a recording: latency per revolution
        lat = latency.measure(ds, refs, segs, setting, config.projection, progress)
        files.append(write_table(out / "latency.csv", lat))
        notes += latency.report(lat)
    if plots:
        name = Path(data).name or str(data)
        files += _plots(table, methods, out, f"{name}, {timed_frames} frames, {setting} setting")
    return BenchmarkResult(table, summary, hist, env, out, files, notes)
