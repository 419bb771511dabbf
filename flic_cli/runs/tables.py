"""The tables of ``flic evaluate``, computed from the pooled per-object and per-frame records.

Scores are in percent with two decimals, as in the paper:

- ``table.csv``: the paper's Table 1, one row per method (IoU_mu no ground, IoU_mu ground, P_mu,
  P_0.50, P_0.75, P_0.95 from the no-ground setting when it was run, else from ground), with the
  95% bootstrap intervals of IoU_mu and P_mu (frames resampled, :mod:`flic_cli.metrics.intervals`);
- ``panoptic.csv``: panoptic quality (PQ, SQ, RQ, with semantic-kitti-api's conventions,
  :mod:`flic_cli.metrics.panoptic`): class-agnostic over the thing objects for every method and
  setting, with the interval of PQ; with oracle semantics also per class and their means;
- ``quality_speed.csv``: IoU_mu (with its interval) against the median time per frame;
- ``ground.csv``: each ground remover of the ground setting against the ground classes
  (precision, recall, F1 of the ground points, share of thing-object points it removed, median
  ms per frame; :mod:`flic_cli.metrics.ground`);
- ``per_setting.csv``: every P_x and the segmentation statistics per method and setting;
- ``per_sequence.csv``, ``by_class.csv``, ``by_distance.csv``: the same scores per sequence, per
  semantic class and per range band of the object's centroid (0-20, 20-40, >40 m).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from flic_cli.classes import CLASS_NAMES
from flic_cli.metrics import DISTANCE_BANDS, IOU_THRESHOLDS, summarize
from flic_cli.metrics.intervals import (
    Interval,
    frame_sums,
    iou_mu_interval,
    p_mu_interval,
    pq_interval,
)

#: Score columns of the summary tables, in percent.
P_COLUMNS: tuple[str, ...] = tuple(f"p_{x:.2f}" for x in IOU_THRESHOLDS)
SCORE_COLUMNS: tuple[str, ...] = ("iou_mu", "p_mu", *P_COLUMNS)

#: Columns of ``table.csv`` (``*_low``/``*_high``: the 95% bootstrap interval).
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
    "iou_mu_no_ground_low",
    "iou_mu_no_ground_high",
    "iou_mu_ground_low",
    "iou_mu_ground_high",
    "p_mu_low",
    "p_mu_high",
    "ose",
    "ose_low",
    "ose_high",
    "use",
    "use_low",
    "use_high",
    "pq_oracle",
    "pq_oracle_low",
    "pq_oracle_high",
    "pq_things_oracle",
    "pq_things_oracle_low",
    "pq_things_oracle_high",
)

#: Resamples and seed of the oracle PQ's percentile bootstrap over frames (:func:`add_oracle_pq`).
PQ_RESAMPLES = 1999
PQ_SEED = 0

#: Columns of ``panoptic.csv``.
PANOPTIC_TABLE_COLUMNS: tuple[str, ...] = (
    "method",
    "semantics",
    "setting",
    "class",
    "pq",
    "sq",
    "rq",
    "iou",
    "tp",
    "fp",
    "fn",
    "pq_low",
    "pq_high",
)

#: Columns of ``ground.csv``.
GROUND_TABLE_COLUMNS: tuple[str, ...] = (
    "remover",
    "frames",
    "precision",
    "recall",
    "f1",
    "things_removed",
    "ms_per_frame_median",
)

#: Columns of ``quality_speed.csv``.
QUALITY_SPEED_COLUMNS: tuple[str, ...] = (
    "method",
    "setting",
    "iou_mu",
    "iou_mu_low",
    "iou_mu_high",
    "ms_per_frame_median",
    "frames_timed",
    "timing",
)


def percent(value: float) -> float:
    """A fraction as a percentage with 2 decimals (nan stays nan)."""
    return float(np.round(100.0 * value, 2)) if np.isfinite(value) else float("nan")


def object_dtypes(methods: list[str], settings: tuple[str, ...], seqs: list[str]) -> dict:
    """Column dtypes of the per-object records (categoricals keep big runs compact)."""
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


def frame_dtypes(methods: list[str], settings: tuple[str, ...], seqs: list[str]) -> dict:
    """Column dtypes of the per-frame records."""
    obj = object_dtypes(methods, settings, seqs)
    return {
        **{k: obj[k] for k in ("method", "setting", "sequence")},
        "frame": "int64",
        "points": "int64",
        "clusters": "int64",
        "objects": "int64",
        "over_segmented": "int64",
        "under_segmented": "int64",
        "seconds": "float64",
        "ground_seconds": "float64",
        "pq_tp": "int64",
        "pq_fp": "int64",
        "pq_fn": "int64",
        "pq_iou_sum": "float64",
        "ose": "float64",
        "use": "float64",
    }


def ground_dtypes(seqs: list[str]) -> dict:
    """Column dtypes of the per-frame ground-extraction records."""
    return {
        "remover": "str",
        "sequence": pd.CategoricalDtype(seqs, ordered=True),
        **{k: "int64" for k in ("frame", "tp", "fp", "fn", "tn", "things", "things_removed")},
        "seconds": "float64",
    }


def ground_table(ground: pd.DataFrame) -> pd.DataFrame:
    """``ground.csv``: one row per remover, its counts pooled over frames (scores in percent)."""
    from flic_cli.metrics.ground import GroundCounts, ground_scores

    rows = []
    for remover, g in ground.groupby("remover", sort=False):
        counts = GroundCounts(
            **{k: int(g[k].sum()) for k in ("tp", "fp", "fn", "tn", "things", "things_removed")},
            frames=len(g),
        )
        scores = ground_scores(counts)
        rows.append(
            {
                "remover": remover,
                "frames": len(g),
                **{k: percent(scores[k] / 100.0) for k in GROUND_TABLE_COLUMNS[2:6]},
                "ms_per_frame_median": round(1000.0 * float(g["seconds"].median()), 4),
            }
        )
    return pd.DataFrame(rows, columns=list(GROUND_TABLE_COLUMNS))


def ground_lines(table: pd.DataFrame) -> list[str]:
    """``ground.csv`` as printed, one line per remover."""
    return [
        f"ground extraction {r.remover}: precision {r.precision:.2f} %, recall {r.recall:.2f} %, "
        f"F1 {r.f1:.2f}, thing-object points removed {r.things_removed:.2f} %, "
        f"{r.ms_per_frame_median:.3g} ms per frame (median of {r.frames})"
        for r in table.itertuples()
    ]


def panoptic_dtypes(methods: list[str], seqs: list[str]) -> dict:
    """Column dtypes of the per-class panoptic counts (oracle semantics)."""
    return {
        "method": pd.CategoricalDtype(methods, ordered=True),
        "sequence": pd.CategoricalDtype(seqs, ordered=True),
        "frame": "int64",
        "class": "int64",
        **{k: "int64" for k in ("tp", "fp", "fn", "sem_tp", "sem_fp", "sem_fn")},
        "iou_sum": "float64",
    }


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


def grouped(
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


def intervals(objects: pd.DataFrame) -> dict[tuple[str, str], dict[str, Interval]]:
    """95% bootstrap intervals of IoU_mu and P_mu per (method, setting), resampling frames."""
    out = {}
    for (method, setting), group in objects.groupby(["method", "setting"], observed=True):
        keys = (group["sequence"].astype(str) + "/" + group["frame"].astype(str)).to_numpy()
        sums = frame_sums(keys, group["iou"].to_numpy())
        out[(str(method), str(setting))] = {
            "iou_mu": iou_mu_interval(sums["iou_sum"], sums["objects"]),
            "p_mu": p_mu_interval(sums["p_sum"], sums["objects"]),
        }
    return out


def paper_table(
    per_setting: pd.DataFrame,
    methods: list[str],
    settings: tuple[str, ...],
    cis: dict[tuple[str, str], dict[str, Interval]] | None = None,
) -> pd.DataFrame:
    """The paper's Table 1 layout from ``per_setting`` rows (scores in percent).

    P_x come from the no-ground setting when it was evaluated (the paper's Table 1 gives them on
    the ground-truth ground removed clouds), else from the ground setting; column ``p_setting``
    says which. ``cis`` (from :func:`intervals`) fills the ``*_low``/``*_high`` columns.
    """
    p_setting = "no-ground" if "no-ground" in settings else "ground"
    index = per_setting.set_index(["method", "setting"])
    cis = cis or {}
    rows = []
    for name in methods:

        def get(setting: str, col: str, name: str = name) -> Any:
            key = (name, setting)
            return index.loc[key, col] if key in index.index else float("nan")

        def bound(setting: str, score: str, end: str, name: str = name) -> float:
            ci = cis.get((name, setting), {}).get(score)
            return percent(getattr(ci, end)) if ci is not None else float("nan")

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
                "iou_mu_no_ground_low": bound("no-ground", "iou_mu", "low"),
                "iou_mu_no_ground_high": bound("no-ground", "iou_mu", "high"),
                "iou_mu_ground_low": bound("ground", "iou_mu", "low"),
                "iou_mu_ground_high": bound("ground", "iou_mu", "high"),
                "p_mu_low": bound(p_setting, "p_mu", "low"),
                "p_mu_high": bound(p_setting, "p_mu", "high"),
            }
        )
    return pd.DataFrame(rows, columns=list(TABLE_COLUMNS))


def add_entropy(table: pd.DataFrame, frames: pd.DataFrame) -> pd.DataFrame:
    """``table`` with OSE and USE (:mod:`flic_cli.metrics.entropy`) of each method's P setting:
    the mean over frames (not percent) and its 95% bootstrap interval (frames resampled)."""
    from flic_cli.metrics.intervals import ratio_interval

    table = table.copy()
    for col in ("ose", "use"):
        values: dict[str, list[float]] = {col: [], f"{col}_low": [], f"{col}_high": []}
        for _, row in table.iterrows():
            sel = frames[
                (frames["method"] == row["method"]) & (frames["setting"] == row["p_setting"])
            ]
            if col not in sel or sel.empty:
                ci = Interval(float("nan"), float("nan"), float("nan"), 0)
            else:
                x = sel[col].to_numpy(dtype=np.float64)
                ci = ratio_interval(x, np.ones_like(x))
            values[col].append(round(ci.estimate, 4))
            values[f"{col}_low"].append(round(ci.low, 4))
            values[f"{col}_high"].append(round(ci.high, 4))
        for key, vals in values.items():
            table[key] = vals
    return table


def add_oracle_pq(
    table: pd.DataFrame, oracle: pd.DataFrame | None, methods: list[str]
) -> pd.DataFrame:
    """``table`` with each method's PQ with oracle semantics (``--semantics oracle``; NaN
    without): the mean over the 19 classes (``pq_oracle``, semantic-kitti-api's PQ) and over the
    8 thing classes (``pq_things_oracle``), in percent, with 95% percentile bootstrap intervals
    (frames resampled, :data:`PQ_RESAMPLES` resamples, seed :data:`PQ_SEED`)."""
    from flic_cli.classes import LEARNING_NAMES, LEARNING_STUFF, LEARNING_THINGS
    from flic_cli.metrics.panoptic import pq_sq_rq

    table = table.copy()
    cols = {c: [float("nan")] * len(table) for c in TABLE_COLUMNS[-6:]}
    n_cls = len(LEARNING_NAMES)
    evaluated = list(LEARNING_THINGS) + list(LEARNING_STUFF)
    rng = np.random.default_rng(PQ_SEED)
    for i, name in enumerate(table["method"]):
        g = None if oracle is None else oracle[oracle["method"] == name]
        if g is None or g.empty:
            continue
        key = g["sequence"].astype(str) + "/" + g["frame"].astype(str)
        frames_, f_idx = np.unique(key.to_numpy(), return_inverse=True)
        arrays = {}
        for f in ("tp", "fp", "fn", "iou_sum"):
            a = np.zeros((frames_.size, n_cls))
            np.add.at(a, (f_idx, g["class"].to_numpy()), g[f].to_numpy(dtype=np.float64))
            arrays[f] = a
        draws = rng.integers(0, frames_.size, size=(PQ_RESAMPLES, frames_.size))

        def means(sums: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
            pq = pq_sq_rq(sums["tp"], sums["fp"], sums["fn"], sums["iou_sum"])[0]
            return pq[..., evaluated].mean(axis=-1), pq[..., list(LEARNING_THINGS)].mean(axis=-1)

        full = means({f: a.sum(axis=0) for f, a in arrays.items()})
        boot = means({f: a[draws].sum(axis=1) for f, a in arrays.items()})
        pairs = (("pq_oracle", full[0], boot[0]), ("pq_things_oracle", full[1], boot[1]))
        for col, est, dist in pairs:
            cols[col][i] = percent(float(est))
            if frames_.size > 1:
                cols[f"{col}_low"][i] = percent(float(np.percentile(dist, 2.5)))
                cols[f"{col}_high"][i] = percent(float(np.percentile(dist, 97.5)))
    for col, vals in cols.items():
        table[col] = vals
    return table


def shown_table(table: pd.DataFrame) -> str:
    """``table.csv`` as printed: each IoU_mu and P_mu with its interval in brackets."""
    shown = pd.DataFrame({"method": table["method"]})
    for col in ("iou_mu_no_ground", "iou_mu_ground", "p_mu"):
        low, high = table[f"{col}_low"], table[f"{col}_high"]
        shown[col] = [
            "-" if pd.isna(v) else f"{v:.2f}" + ("" if pd.isna(lo) else f" [{lo:.1f}, {hi:.1f}]")
            for v, lo, hi in zip(table[col], low, high, strict=True)
        ]
    for col in ("p_0.50", "p_0.75", "p_0.95"):
        shown[col] = ["-" if pd.isna(v) else f"{v:.2f}" for v in table[col]]
    for col, label in (("pq_oracle", "PQ_oracle"), ("pq_things_oracle", "PQ_th_oracle")):
        if col in table and table[col].notna().any():
            shown[label] = [
                "-"
                if pd.isna(v)
                else f"{v:.2f}" + ("" if pd.isna(lo) else f" [{lo:.1f}, {hi:.1f}]")
                for v, lo, hi in zip(
                    table[col], table[f"{col}_low"], table[f"{col}_high"], strict=True
                )
            ]
    for col in ("ose", "use"):
        if col in table:
            shown[col.upper()] = [
                "-"
                if pd.isna(v)
                else f"{v:.2f}" + ("" if pd.isna(lo) else f" [{lo:.1f}, {hi:.1f}]")
                for v, lo, hi in zip(
                    table[col], table[f"{col}_low"], table[f"{col}_high"], strict=True
                )
            ]
    shown["objects"] = table["objects"]
    return shown.to_string(index=False)


def panoptic_table(
    frames: pd.DataFrame, oracle: pd.DataFrame | None, methods: list[str]
) -> pd.DataFrame:
    """``panoptic.csv``: class-agnostic PQ per method and setting (from the per-frame counts),
    and with oracle semantics per class and their means (scores in percent)."""
    from flic_cli.classes import LEARNING_NAMES, LEARNING_STUFF, LEARNING_THINGS
    from flic_cli.metrics.panoptic import (
        PanopticCounts,
        class_scores,
        panoptic_summary,
        pq_sq_rq,
    )

    rows = []
    for (method, setting), g in frames.groupby(["method", "setting"], observed=True, sort=True):
        tp, fp, fn, iou = (
            int(g["pq_tp"].sum()),
            int(g["pq_fp"].sum()),
            int(g["pq_fn"].sum()),
            float(g["pq_iou_sum"].sum()),
        )
        pq, sq, rq = pq_sq_rq(tp, fp, fn, iou)
        ci = pq_interval(g["pq_iou_sum"], g["pq_tp"], g["pq_fp"], g["pq_fn"])
        rows.append(
            {
                "method": method,
                "semantics": "none",
                "setting": setting,
                "class": "things",
                "pq": percent(pq),
                "sq": percent(sq),
                "rq": percent(rq),
                "iou": float("nan"),
                "tp": tp,
                "fp": fp,
                "fn": fn,
                "pq_low": percent(ci.low),
                "pq_high": percent(ci.high),
            }
        )
    if oracle is not None:
        names = LEARNING_NAMES
        for method in methods:
            g = oracle[oracle["method"] == method]
            if g.empty:
                continue
            n = len(names)
            by_class = g.groupby("class")
            counts = PanopticCounts(
                *(
                    by_class[f].sum().reindex(range(n), fill_value=0).to_numpy()
                    for f in ("tp", "fp", "fn", "iou_sum", "sem_tp", "sem_fp", "sem_fn")
                )
            )
            scores = class_scores(counts)
            for c in range(1, n):
                gc = g[g["class"] == c]
                ci = pq_interval(gc["iou_sum"], gc["tp"], gc["fp"], gc["fn"])
                rows.append(
                    {
                        "method": method,
                        "semantics": "oracle",
                        "setting": "-",
                        "class": names[c],
                        "pq": percent(scores["pq"][c]),
                        "sq": percent(scores["sq"][c]),
                        "rq": percent(scores["rq"][c]),
                        "iou": percent(scores["iou"][c]),
                        "tp": int(counts.tp[c]),
                        "fp": int(counts.fp[c]),
                        "fn": int(counts.fn[c]),
                        "pq_low": percent(ci.low),
                        "pq_high": percent(ci.high),
                    }
                )
            summary = panoptic_summary(counts)
            every = list(range(1, n))
            for label, pq, sq, rq, iou, members in (
                ("mean", "pq_mean", "sq_mean", "rq_mean", "iou_mean", every),
                ("things", "pq_things", "sq_things", "rq_things", None, list(LEARNING_THINGS)),
                ("stuff", "pq_stuff", "sq_stuff", "rq_stuff", None, list(LEARNING_STUFF)),
                ("mean (PQ dagger)", "pq_dagger", None, None, None, every),
            ):
                rows.append(
                    {
                        "method": method,
                        "semantics": "oracle",
                        "setting": "-",
                        "class": label,
                        "pq": percent(summary[pq]),
                        "sq": percent(summary[sq]) if sq else float("nan"),
                        "rq": percent(summary[rq]) if rq else float("nan"),
                        "iou": percent(summary[iou]) if iou else float("nan"),
                        "tp": int(counts.tp[members].sum()),
                        "fp": int(counts.fp[members].sum()),
                        "fn": int(counts.fn[members].sum()),
                        "pq_low": float("nan"),
                        "pq_high": float("nan"),
                    }
                )
    return pd.DataFrame(rows, columns=list(PANOPTIC_TABLE_COLUMNS))


def quality_speed_table(
    table: pd.DataFrame, frames: pd.DataFrame, runtimes: pd.DataFrame | None = None
) -> pd.DataFrame:
    """``quality_speed.csv``: IoU_mu (the P setting's, with its interval) against the median
    time per frame: from a ``flic benchmark`` summary when given (``runtimes``), else from the
    evaluate run itself (the same setting; less controlled: other work shares the cores)."""
    rows = []
    for _, row in table.iterrows():
        setting = row["p_setting"]
        key = "no_ground" if setting == "no-ground" else "ground"
        if runtimes is not None and row["method"] in set(runtimes["method"]):
            bench = runtimes.set_index("method").loc[row["method"]]
            ms, n, timing = float(bench["median_ms"]), int(bench["frames"]), "flic benchmark"
        else:
            sel = frames[(frames["method"] == row["method"]) & (frames["setting"] == setting)]
            ms = 1000.0 * float(sel["seconds"].median()) if len(sel) else float("nan")
            n, timing = len(sel), f"flic evaluate ({setting} setting)"
        rows.append(
            {
                "method": row["method"],
                "setting": setting,
                "iou_mu": row[f"iou_mu_{key}"],
                "iou_mu_low": row[f"iou_mu_{key}_low"],
                "iou_mu_high": row[f"iou_mu_{key}_high"],
                "ms_per_frame_median": round(ms, 4),
                "frames_timed": n,
                "timing": timing,
            }
        )
    return pd.DataFrame(rows, columns=list(QUALITY_SPEED_COLUMNS))


def all_tables(
    objects: pd.DataFrame,
    frames: pd.DataFrame,
    methods: list[str],
    settings: tuple[str, ...],
    oracle: pd.DataFrame | None = None,
    runtimes: pd.DataFrame | None = None,
    ground: pd.DataFrame | None = None,
) -> dict[str, pd.DataFrame]:
    """Every table of ``flic evaluate`` by file name (``table.csv`` last)."""
    per_setting = grouped(objects, ["method", "setting"], frames)
    table = paper_table(per_setting, methods, settings, intervals(objects))
    table = add_oracle_pq(add_entropy(table, frames), oracle, methods)
    return {
        "per_object.csv": objects,
        "per_frame.csv": frames,
        "per_setting.csv": per_setting,
        "per_sequence.csv": grouped(objects, ["method", "setting", "sequence"], frames),
        "by_class.csv": grouped(objects, ["method", "setting", "class", "class_name"]),
        "by_distance.csv": grouped(objects, ["method", "setting", "band"]),
        "panoptic.csv": panoptic_table(frames, oracle, methods),
        "quality_speed.csv": quality_speed_table(table, frames, runtimes),
        **({"ground.csv": ground_table(ground)} if ground is not None and len(ground) else {}),
        "table.csv": table,
    }
