"""The tables of ``flic evaluate``, computed from the pooled per-object and per-frame records.

Scores are in percent with two decimals, as in the paper:

- ``table.csv``: the paper's Table 1, one row per method (IoU_mu no ground, IoU_mu ground, P_mu,
  P_0.50, P_0.75, P_0.95 from the no-ground setting when it was run, else from ground);
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


def all_tables(
    objects: pd.DataFrame,
    frames: pd.DataFrame,
    methods: list[str],
    settings: tuple[str, ...],
) -> dict[str, pd.DataFrame]:
    """Every table of ``flic evaluate`` by file name (``table.csv`` last)."""
    per_setting = grouped(objects, ["method", "setting"], frames)
    return {
        "per_object.csv": objects,
        "per_frame.csv": frames,
        "per_setting.csv": per_setting,
        "per_sequence.csv": grouped(objects, ["method", "setting", "sequence"], frames),
        "by_class.csv": grouped(objects, ["method", "setting", "class", "class_name"]),
        "by_distance.csv": grouped(objects, ["method", "setting", "band"]),
        "table.csv": paper_table(per_setting, methods, settings),
    }
