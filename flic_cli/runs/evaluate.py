"""``flic evaluate``: the paper's quality protocol (SPEC section 4) over a whole dataset.

The unit of work is one frame: a worker (:func:`evaluate_frame`) reads the frame once, prepares it
once per setting, runs every method on it and scores the labels with
:func:`flic_cli.metrics.match_objects` and :func:`flic_cli.metrics.segmentation_stats`. It returns
small per-object and per-frame records, never point clouds.

The parent streams each finished frame to ``<out>/parts/<seq>/<frame>.objects.csv`` and
``<frame>.frames.csv`` (each written atomically, the frames file last: a frame is done once its
frames file exists). ``<out>/run.json`` holds the run's parameters; ``--resume`` skips the done
frames of a run with the same parameters. The tables are computed from the parts of the selected
frames, sorted, so they do not depend on the order in which frames finished, on ``--jobs`` or on
interruptions; every table is written atomically.

Output (scores in percent, two decimals, as in the paper):

- ``table.csv``: the paper's Table 1, one row per method (IoU_mu no ground, IoU_mu ground, P_mu,
  P_0.50, P_0.75, P_0.95 from the no-ground setting when it was run, else from ground).
- ``per_setting.csv``: every P_x and the segmentation statistics per method and setting.
- ``per_sequence.csv``, ``by_class.csv``, ``by_distance.csv``: the same scores per sequence, per
  semantic class and per range band of the object's centroid (0-20, 20-40, >40 m).
- ``per_object.csv``: one row per ground-truth object, method and setting (IoU as a fraction), from
  which any other statistic can be derived; ``per_frame.csv``: clusters, over- and
  under-segmentation and segmentation time per frame, method and setting.
"""

from __future__ import annotations

import csv
import functools
import io
import json
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

from flic_cli.classes import CLASS_NAMES, class_name
from flic_cli.errors import FlicInputError
from flic_cli.io import atomic_write, open_dataset, read_scan
from flic_cli.io.base import Frame, FrameRef
from flic_cli.metrics import (
    DISTANCE_BANDS,
    IOU_THRESHOLDS,
    distance_band,
    match_objects,
    segmentation_stats,
    summarize,
)
from flic_cli.runs.parallel import imap_frames
from flic_cli.runs.pipeline import make_segmenter, prepare

#: The methods of the paper's Table 1, in its order.
DEFAULT_METHODS: tuple[str, ...] = ("bogoslavskyi", "flic0", "flic1", "flic6", "flic14", "dbscan")

#: ``--setting`` of evaluate: one setting or both in one pass (each frame read once).
EVAL_SETTINGS: dict[str, tuple[str, ...]] = {
    "no-ground": ("no-ground",),
    "ground": ("ground",),
    "both": ("no-ground", "ground"),
}

#: Columns of ``per_object.csv`` (and of the per-frame object parts).
OBJECT_COLUMNS: tuple[str, ...] = (
    "method",
    "setting",
    "sequence",
    "frame",
    "instance",
    "class",
    "class_name",
    "points",
    "distance_m",
    "band",
    "cluster",
    "overlap",
    "iou",
)

#: Columns of ``per_frame.csv`` (and of the per-frame frame parts).
FRAME_COLUMNS: tuple[str, ...] = (
    "method",
    "setting",
    "sequence",
    "frame",
    "points",
    "clusters",
    "objects",
    "over_segmented",
    "under_segmented",
    "seconds",
)

#: Score columns of the summary tables, in percent.
P_COLUMNS: tuple[str, ...] = tuple(f"p_{x:.2f}" for x in IOU_THRESHOLDS)
SCORE_COLUMNS: tuple[str, ...] = ("iou_mu", "p_mu", *P_COLUMNS)

#: Columns of ``table.csv``.
TABLE_COLUMNS: tuple[str, ...] = (
    "method",
    "iou_mu_no_ground",
    "iou_mu_ground",
    "p_mu",
    "p_0.50",
    "p_0.75",
    "p_0.95",
    "objects",
    "p_setting",
)

#: Frames read per chunk when the parts are gathered into the tables.
_CHUNK_FRAMES = 2000

PARTS = "parts"
RUN_FILE = "run.json"


# ---------------------------------------------------------------------------------------------
# Worker side
# ---------------------------------------------------------------------------------------------


@dataclass
class FrameResult:
    """What a worker returns for one frame: column lists, or the input error it met.

    Attributes
    ----------
    sequence, frame : which frame.
    objects : per-object rows as column lists (keys :data:`OBJECT_COLUMNS`).
    frames : per-frame rows as column lists (keys :data:`FRAME_COLUMNS`).
    error : ``(path, reason)`` of a :class:`FlicInputError`, re-raised by the parent (custom
        exceptions do not always survive the trip back from another process).
    """

    sequence: str
    frame: int
    objects: dict[str, list] = field(default_factory=dict)
    frames: dict[str, list] = field(default_factory=dict)
    error: tuple[str | None, str] | None = None

    def raise_error(self) -> None:
        """Raise the worker's input error, if any, in this process."""
        if self.error is not None:
            raise FlicInputError(self.error[0], self.error[1])


def load_labelled_frame(ref: FrameRef) -> Frame:
    """Read a SemanticKITTI frame with its labels from its reference alone (in a worker).

    Raises
    ------
    FlicInputError
        When the frame is not a SemanticKITTI scan with a ``.label`` file, or cannot be read.
    """
    if ref.format != "semantickitti" or ref.label_path is None:
        raise FlicInputError(
            ref.path,
            "has no ground-truth labels: evaluation needs labelled SemanticKITTI data "
            "(labels/<frame>.label)",
        )
    scan = read_scan(ref.path, ref.label_path)
    return Frame(ref, scan.points, scan.labels, finite=scan.finite)


def evaluate_frame(
    ref: FrameRef,
    cfg: dict[str, Any],
    methods: list[str] | tuple[str, ...],
    settings: list[str] | tuple[str, ...],
    ground_remover: str = "paper",
) -> FrameResult:
    """Evaluate every method in every setting on one frame (read once, prepared once per setting).

    Parameters
    ----------
    ref : the frame (must have a ``.label`` file).
    cfg : the loaded config (methods, ground removers, projection).
    methods : method variant names.
    settings : ``"no-ground"`` and/or ``"ground"``.
    ground_remover : see :func:`flic_cli.runs.pipeline.make_segmenter`.

    Returns
    -------
    FrameResult
        Per-object rows (one per ground-truth object with >= 100 points, method and setting) and
        per-frame rows (one per method and setting); input errors are returned, not raised.
    """
    try:
        return _evaluate_frame(ref, cfg, methods, settings, ground_remover)
    except FlicInputError as exc:
        return FrameResult(
            ref.sequence,
            ref.frame,
            error=(None if exc.path is None else str(exc.path), exc.reason),
        )


def _evaluate_frame(
    ref: FrameRef,
    cfg: dict[str, Any],
    methods: list[str] | tuple[str, ...],
    settings: list[str] | tuple[str, ...],
    ground_remover: str,
) -> FrameResult:
    frame = load_labelled_frame(ref)
    objects: dict[str, list] = {c: [] for c in OBJECT_COLUMNS}
    frames: dict[str, list] = {c: [] for c in FRAME_COLUMNS}
    for setting in settings:
        prep = prepare(frame, setting, cfg.get("projection", {}))
        assert prep.labels is not None  # load_labelled_frame guarantees labels
        # The ground mask depends only on the remover: extract it once per remover, and count
        # its time in every method that uses it (as if each method ran alone).
        grounds: dict[str | None, tuple[Any, float]] = {}
        for name in methods:
            segmenter = make_segmenter(cfg, name, setting, ground_remover)
            if segmenter.ground_name not in grounds:
                start = time.perf_counter()
                mask = segmenter.extract_ground(prep.image, prep.points)
                grounds[segmenter.ground_name] = (mask, time.perf_counter() - start)
            ground, ground_seconds = grounds[segmenter.ground_name]
            start = time.perf_counter()
            labels = segmenter.method.segment(prep.image, prep.points, ground)
            seconds = time.perf_counter() - start + ground_seconds
            matches = match_objects(prep.labels, labels, prep.points)
            stats = segmentation_stats(prep.labels, labels)
            n = len(matches)
            objects["method"] += [name] * n
            objects["setting"] += [setting] * n
            objects["sequence"] += [ref.sequence] * n
            objects["frame"] += [ref.frame] * n
            objects["instance"] += matches.instance.tolist()
            objects["class"] += matches.semantic.tolist()
            objects["class_name"] += [class_name(c) for c in matches.semantic]
            objects["points"] += matches.n_points.tolist()
            objects["distance_m"] += np.round(matches.distance, 3).tolist()
            objects["band"] += distance_band(matches.distance).tolist()
            objects["cluster"] += matches.cluster.tolist()
            objects["overlap"] += matches.overlap.tolist()
            objects["iou"] += matches.iou.tolist()
            for key, value in (
                ("method", name),
                ("setting", setting),
                ("sequence", ref.sequence),
                ("frame", ref.frame),
                ("points", int(prep.points.shape[0])),
                ("clusters", stats["clusters"]),
                ("objects", stats["objects"]),
                ("over_segmented", stats["over_segmented"]),
                ("under_segmented", stats["under_segmented"]),
                ("seconds", round(seconds, 6)),
            ):
                frames[key].append(value)
    return FrameResult(ref.sequence, ref.frame, objects, frames)


# ---------------------------------------------------------------------------------------------
# Parts on disk: one pair of small CSVs per frame
# ---------------------------------------------------------------------------------------------


def _part_paths(parts: Path, sequence: str, frame: int) -> tuple[Path, Path]:
    folder = parts / sequence
    return folder / f"{frame:06d}.objects.csv", folder / f"{frame:06d}.frames.csv"


def _write_csv_part(path: Path, columns: tuple[str, ...], rows: dict[str, list]) -> None:
    with atomic_write(path) as tmp:
        with open(tmp, "w", newline="", encoding="utf-8") as f:
            writer = csv.writer(f, lineterminator="\n")
            writer.writerow(columns)
            writer.writerows(zip(*(rows[c] for c in columns), strict=True))


def write_part(parts: Path, result: FrameResult) -> None:
    """Store one frame's rows: the objects file, then the frames file (which marks it done)."""
    obj_path, frame_path = _part_paths(parts, result.sequence, result.frame)
    _write_csv_part(obj_path, OBJECT_COLUMNS, result.objects)
    _write_csv_part(frame_path, FRAME_COLUMNS, result.frames)


def done_frames(parts: Path) -> set[tuple[str, int]]:
    """``(sequence, frame)`` of every frame whose parts are complete."""
    done = set()
    for path in parts.glob("*/*.frames.csv"):
        stem = path.name.split(".", 1)[0]
        if stem.isdigit():
            done.add((path.parent.name, int(stem)))
    return done


def _clean_temporaries(parts: Path) -> None:
    """Remove temporary files that a killed run left behind."""
    for path in parts.glob("*/.*.tmp-*"):
        path.unlink(missing_ok=True)


def _read_parts(
    parts: Path,
    keys: list[tuple[str, int]],
    kind: str,
    columns: tuple[str, ...],
    dtypes: dict[str, Any],
) -> pd.DataFrame:
    """Gather the ``kind`` (``objects``/``frames``) parts of ``keys`` into one DataFrame.

    Read in chunks of frames with fixed categorical dtypes, so that memory holds the compact
    table only (never the text of all parts at once).
    """
    header = ",".join(columns) + "\n"
    chunks = []
    for start in range(0, len(keys), _CHUNK_FRAMES):
        text = [header]
        for sequence, frame in keys[start : start + _CHUNK_FRAMES]:
            path = _part_paths(parts, sequence, frame)[0 if kind == "objects" else 1]
            try:
                content = path.read_text(encoding="utf-8")
            except OSError:
                raise FlicInputError(
                    path, "part file is missing or unreadable (rerun with --resume)"
                ) from None
            first, _, body = content.partition("\n")
            if first + "\n" != header:
                raise FlicInputError(
                    path,
                    "part file has other columns than this version of flic writes; "
                    "delete the parts folder or use another --out",
                )
            text.append(body)
        chunks.append(pd.read_csv(io.StringIO("".join(text)), dtype=dtypes, keep_default_na=False))
    if not chunks:
        return pd.DataFrame({c: pd.Series(dtype=dtypes.get(c, "float64")) for c in columns})
    return pd.concat(chunks, ignore_index=True)


# ---------------------------------------------------------------------------------------------
# Tables
# ---------------------------------------------------------------------------------------------


def percent(value: float) -> float:
    """A fraction as a percentage with 2 decimals (nan stays nan)."""
    return float(np.round(100.0 * value, 2)) if np.isfinite(value) else float("nan")


def _scores(ious: np.ndarray) -> dict[str, Any]:
    """:func:`summarize` in percent with two decimals (``objects`` unchanged)."""
    s = summarize(ious)
    out: dict[str, Any] = {"objects": int(s["objects"])}
    out.update({c: percent(float(s[c])) for c in SCORE_COLUMNS})
    return out


def _frame_stats(frames: pd.DataFrame) -> dict[str, Any]:
    return {
        "frames": int(len(frames)),
        "clusters_per_frame": round(float(frames["clusters"].mean()), 2) if len(frames) else 0.0,
        "over_segmented": int(frames["over_segmented"].sum()),
        "under_segmented": int(frames["under_segmented"].sum()),
        "ms_per_frame_median": (
            round(1000.0 * float(frames["seconds"].median()), 3) if len(frames) else 0.0
        ),
    }


def _grouped(
    objects: pd.DataFrame, by: list[str], frames: pd.DataFrame | None = None
) -> pd.DataFrame:
    """Scores per group of ``by`` (and, with ``frames``, the segmentation statistics)."""
    rows = []
    obj_groups = {
        (k if isinstance(k, tuple) else (k,)): g["iou"].to_numpy()
        for k, g in objects.groupby(by, observed=True, sort=True)
    }
    frame_groups: dict[tuple, pd.DataFrame] = {}
    if frames is not None:
        frame_groups = {
            (k if isinstance(k, tuple) else (k,)): g
            for k, g in frames.groupby(by, observed=True, sort=True)
        }
    keys = sorted(set(obj_groups) | set(frame_groups), key=lambda k: _sort_key(objects, by, k))
    for key in keys:
        row: dict[str, Any] = dict(zip(by, key, strict=True))
        if frames is not None:
            row.update(_frame_stats(frame_groups.get(key, frames.iloc[:0])))
        row.update(_scores(obj_groups.get(key, np.zeros(0))))
        rows.append(row)
    cols = [*by, *(["frames"] if frames is not None else []), "objects", *SCORE_COLUMNS]
    if frames is not None:
        cols += ["clusters_per_frame", "over_segmented", "under_segmented", "ms_per_frame_median"]
    return pd.DataFrame(rows, columns=cols)


def _sort_key(objects: pd.DataFrame, by: list[str], key: tuple) -> tuple:
    """Categories in their declared order, everything else by value."""
    out = []
    for col, value in zip(by, key, strict=True):
        dtype = objects[col].dtype
        if isinstance(dtype, pd.CategoricalDtype):
            out.append(list(dtype.categories).index(value))
        else:
            out.append(value)
    return tuple(out)


def paper_table(
    per_setting: pd.DataFrame, methods: list[str], settings: tuple[str, ...]
) -> pd.DataFrame:
    """The paper's Table 1 layout from ``per_setting`` rows (scores in percent).

    P_x come from the no-ground setting when it was evaluated (the paper's Table 1 gives them on
    the ground-truth ground removed clouds), else from the ground setting; column ``p_setting``
    says which.
    """
    p_setting = "no-ground" if "no-ground" in settings else "ground"
    index = per_setting.set_index(["method", "setting"])
    rows = []
    for name in methods:

        def get(setting: str, col: str, name: str = name) -> Any:
            key = (name, setting)
            return index.loc[key, col] if key in index.index else float("nan")

        objects = get(p_setting, "objects")
        rows.append(
            {
                "method": name,
                "iou_mu_no_ground": get("no-ground", "iou_mu"),
                "iou_mu_ground": get("ground", "iou_mu"),
                "p_mu": get(p_setting, "p_mu"),
                "p_0.50": get(p_setting, "p_0.50"),
                "p_0.75": get(p_setting, "p_0.75"),
                "p_0.95": get(p_setting, "p_0.95"),
                "objects": int(objects) if pd.notna(objects) else 0,
                "p_setting": p_setting,
            }
        )
    return pd.DataFrame(rows, columns=list(TABLE_COLUMNS))


def _write_table(df: pd.DataFrame, path: Path) -> None:
    with atomic_write(path) as tmp:
        df.to_csv(tmp, index=False)


# ---------------------------------------------------------------------------------------------
# The run
# ---------------------------------------------------------------------------------------------


@dataclass
class EvaluateResult:
    """What :func:`run_evaluate` produced.

    Attributes
    ----------
    table : the paper's Table 1 layout (``table.csv``).
    caption : one line describing the table.
    out : output folder.
    frames : frames evaluated (selected and labelled).
    resumed : frames taken from an earlier run's parts.
    skipped : frames without ``.label`` left out (``--skip-missing``).
    files : the tables written.
    """

    table: pd.DataFrame
    caption: str
    out: Path
    frames: int
    resumed: int
    skipped: int
    files: list[Path]

    def text(self) -> str:
        """Caption and table, ready to print."""
        shown = self.table.drop(columns=["p_setting"])
        text = shown.to_string(index=False, na_rep="-", float_format=lambda v: f"{v:.2f}")
        return f"{self.caption}\n{text}"


def run_parameters(
    data: Path,
    cfg: dict[str, Any],
    methods: list[str],
    settings: tuple[str, ...],
    ground_remover: str,
    sequences: list[str] | None,
    frames: tuple[int | None, int | None] | None,
    command: str = "evaluate",
) -> dict[str, Any]:
    """The parameters that decide a run's results (stored in ``run.json``; JSON-normalised)."""
    params = {
        "command": command,
        "data": str(Path(data).resolve()),
        "sequences": None if sequences is None else sorted(sequences),
        "frames": None if frames is None else list(frames),
        "methods": list(methods),
        "settings": list(settings),
        "ground_remover": ground_remover,
        "config": {
            "projection": cfg.get("projection", {}),
            "ground": cfg.get("ground", {}),
            "methods": {m: cfg["methods"][m] for m in methods},
        },
    }
    return json.loads(json.dumps(params, default=str))


def _differences(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    return sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))


def prepare_out(out: Path, params: dict[str, Any], resume: bool) -> set[tuple[str, int]]:
    """Check ``out`` against an earlier run, write ``run.json``; the frames already done.

    Raises
    ------
    FlicInputError
        When ``out`` holds parts of an earlier run and ``resume`` is false, or of a run with other
        parameters.
    """
    parts = out / PARTS
    run_file = out / RUN_FILE
    has_parts = parts.is_dir() and any(parts.glob("*/*.csv"))
    old = None
    if run_file.is_file():
        try:
            old = json.loads(run_file.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            old = None
    if has_parts:
        if old is None:
            raise FlicInputError(
                parts,
                "holds per-frame results of an unknown run (no valid run.json); use another --out",
            )
        diff = _differences(old, params)
        if diff:
            raise FlicInputError(
                out,
                f"holds results of a different run ({', '.join(diff)} differ); "
                "use another --out, or repeat that run's options with --resume",
            )
        if not resume:
            raise FlicInputError(
                out,
                "holds results of this run already: add --resume to continue it "
                "(finished frames are kept), or use another --out",
            )
        _clean_temporaries(parts)
        return done_frames(parts)
    with atomic_write(run_file) as tmp:
        tmp.write_text(json.dumps(params, indent=2, sort_keys=True) + "\n", encoding="utf-8")
    return set()


def select_labelled(
    data: Path,
    sequences: list[str] | None,
    frames: tuple[int | None, int | None] | None,
    skip_missing: bool,
) -> tuple[list[FrameRef], int]:
    """The selected frames that have labels, and how many were skipped for lacking them.

    Raises
    ------
    FlicInputError
        Naming the missing ``.label`` files (unless ``skip_missing``), or when no frame has labels.
    """
    ds = open_dataset(data, sequences, frames, require_labels=not skip_missing)
    refs = ds.refs()
    labelled = [r for r in refs if r.label_path is not None]
    if not labelled:
        raise FlicInputError(
            data,
            "no selected frame has ground-truth labels: evaluation needs labelled SemanticKITTI "
            "data (sequences/NN/labels/*.label)",
        )
    return labelled, len(refs) - len(labelled)


def _object_dtypes(methods: list[str], settings: tuple[str, ...], seqs: list[str]) -> dict:
    return {
        "method": pd.CategoricalDtype(methods, ordered=True),
        "setting": pd.CategoricalDtype(list(settings), ordered=True),
        "sequence": pd.CategoricalDtype(seqs, ordered=True),
        "frame": "int64",
        "instance": "int64",
        "class": "int64",
        "class_name": pd.CategoricalDtype(sorted(set(CLASS_NAMES.values()))),
        "points": "int64",
        "distance_m": "float64",
        "band": pd.CategoricalDtype([*DISTANCE_BANDS, "n/a"], ordered=True),
        "cluster": "int64",
        "overlap": "int64",
        "iou": "float64",
    }


def run_evaluate(
    data: Path,
    out: Path,
    methods: list[str],
    cfg: dict[str, Any],
    setting: str = "both",
    sequences: list[str] | None = None,
    frames: tuple[int | None, int | None] | None = None,
    ground_remover: str = "paper",
    jobs: int = 1,
    scheduler: str | None = None,
    resume: bool = False,
    skip_missing: bool = False,
    progress: bool = True,
    on_start: Callable[[int, int, int], None] | None = None,
) -> EvaluateResult:
    """Evaluate methods on every selected labelled frame and write the tables to ``out``.

    Parameters
    ----------
    data : SemanticKITTI root or sequence folder, with labels.
    out : output folder (``parts/``, ``run.json`` and the tables).
    methods : method variant names of the config.
    cfg : the loaded config.
    setting : ``"no-ground"``, ``"ground"`` or ``"both"``.
    sequences, frames : selection (see :func:`flic_cli.io.open_dataset`).
    ground_remover : ground extraction of the ground setting: ``"paper"`` (the protocol: the
        paper's for every method) or ``"own"`` (each method's ``ground`` key).
    jobs : local processes (see :func:`flic_cli.runs.parallel.imap_frames`).
    scheduler : dask.distributed scheduler address, instead of local processes.
    resume : continue the run stored in ``out`` (same parameters), skipping its finished frames.
    skip_missing : evaluate only the frames that have a ``.label`` file instead of failing.
    progress : show a progress bar.
    on_start : called with (frames selected, frames already done, frames skipped) before the work
        starts (the CLI prints a line).

    Returns
    -------
    EvaluateResult

    Raises
    ------
    FlicInputError
        On bad input: unknown setting or method, missing labels, unreadable frames, an ``out``
        folder holding another run.
    """
    if setting not in EVAL_SETTINGS:
        raise FlicInputError(None, f"--setting must be one of {', '.join(EVAL_SETTINGS)}")
    settings = EVAL_SETTINGS[setting]
    methods = list(dict.fromkeys(methods))
    for name in methods:  # fail on a bad config before any frame is read
        for s in settings:
            make_segmenter(cfg, name, s, ground_remover)
    refs, skipped = select_labelled(data, sequences, frames, skip_missing)
    params = run_parameters(data, cfg, methods, settings, ground_remover, sequences, frames)
    out = Path(out)
    done = prepare_out(out, params, resume)
    parts = out / PARTS
    keys = [(r.sequence, r.frame) for r in refs]
    todo = [r for r in refs if (r.sequence, r.frame) not in done]
    resumed = len(refs) - len(todo)
    if on_start is not None:
        on_start(len(refs), resumed, skipped)

    worker = functools.partial(
        evaluate_frame,
        cfg=cfg,
        methods=tuple(methods),
        settings=settings,
        ground_remover=ground_remover,
    )
    _stream(worker, todo, parts, jobs, scheduler, progress, resumed, len(refs))
    return _tables(out, parts, keys, methods, settings, ground_remover, resumed, skipped)


def _stream(
    worker: Callable[[FrameRef], FrameResult],
    todo: Iterable[FrameRef],
    parts: Path,
    jobs: int,
    scheduler: str | None,
    progress: bool,
    initial: int,
    total: int,
) -> None:
    """Run the worker over the frames, writing each finished frame's parts at once."""
    with tqdm(
        total=total, initial=initial, desc="evaluate", unit="frame", disable=not progress
    ) as bar:
        for result in imap_frames(worker, todo, jobs, scheduler):
            result.raise_error()
            write_part(parts, result)
            bar.update(1)


def _tables(
    out: Path,
    parts: Path,
    keys: list[tuple[str, int]],
    methods: list[str],
    settings: tuple[str, ...],
    ground_remover: str,
    resumed: int,
    skipped: int,
) -> EvaluateResult:
    """Read the parts of the selected frames and write every table."""
    seqs = sorted({k[0] for k in keys})
    obj_dtypes = _object_dtypes(methods, settings, seqs)
    frame_dtypes = {
        **{k: obj_dtypes[k] for k in ("method", "setting", "sequence")},
        "frame": "int64",
        "points": "int64",
        "clusters": "int64",
        "objects": "int64",
        "over_segmented": "int64",
        "under_segmented": "int64",
        "seconds": "float64",
    }
    objects = _read_parts(parts, keys, "objects", OBJECT_COLUMNS, obj_dtypes)
    frames = _read_parts(parts, keys, "frames", FRAME_COLUMNS, frame_dtypes)
    objects = objects.sort_values(
        ["method", "setting", "sequence", "frame", "instance", "class"], kind="stable"
    ).reset_index(drop=True)
    frames = frames.sort_values(["method", "setting", "sequence", "frame"], kind="stable")
    frames = frames.reset_index(drop=True)

    per_setting = _grouped(objects, ["method", "setting"], frames)
    per_sequence = _grouped(objects, ["method", "setting", "sequence"], frames)
    by_class = _grouped(objects, ["method", "setting", "class", "class_name"])
    by_distance = _grouped(objects, ["method", "setting", "band"])
    table = paper_table(per_setting, methods, settings)

    files = []
    for name, df in (
        ("per_object.csv", objects),
        ("per_frame.csv", frames),
        ("per_setting.csv", per_setting),
        ("per_sequence.csv", per_sequence),
        ("by_class.csv", by_class),
        ("by_distance.csv", by_distance),
        ("table.csv", table),
    ):
        _write_table(df, out / name)
        files.append(out / name)

    p_setting = table["p_setting"].iloc[0] if len(table) else "no-ground"
    n_objects = int(table["objects"].max()) if len(table) else 0
    remover = {"paper": "the paper's", "own": "each method's own"}.get(
        ground_remover, ground_remover
    )
    caption = (
        f"SPEC 4 protocol, {len(keys)} frames, {n_objects} GT objects (>= 100 points); "
        f"IoU_mu and P_x in %, P_x from the {p_setting} setting"
        + (f"; ground setting with {remover} ground extraction" if "ground" in settings else "")
    )
    return EvaluateResult(table, caption, out, len(keys), resumed, skipped, files)
