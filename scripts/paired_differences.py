"""Which differences between methods in an evaluate run are significant: paired bootstrap.

Two methods are scored on the same objects of the same frames, so their difference is far less
uncertain than their two intervals side by side suggest. For every pair of methods and each
setting, the difference of IoU_mu (and of P_mu) is resampled by frames (both methods' per-frame
sums drawn together; :func:`flic_cli.metrics.intervals.frame_sums`) with scipy.stats.bootstrap
(BCa, 9999 resamples, seed 0); a difference is significant when its 95 % interval excludes 0.

With ``--settings`` it pairs each method with itself instead: its no-ground minus its ground
IoU_mu (and P_mu), the gap that a ground remover leaves (issue 8's target: within 1.5 points),
with the interval of that gap over the frames (an evaluate run with ``--setting both``).

Usage: python scripts/paired_differences.py results/evaluate     (writes differences.csv there)
       python scripts/paired_differences.py /tmp/ev_column --settings \\
           --out results/ground/gap_intervals_column.csv
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from flic_cli.io.atomic import write_table
from flic_cli.metrics.intervals import _RNG_KEYWORD, N_RESAMPLES, SEED, frame_sums


def paired(a: dict[str, np.ndarray], b: dict[str, np.ndarray], key: str) -> tuple[float, ...]:
    """Estimate and 95 % interval of (sum a / objects) - (sum b / objects), frames resampled."""

    def diff(sa: np.ndarray, sb: np.ndarray, n: np.ndarray, axis: int = -1) -> np.ndarray:
        return (sa.sum(axis=axis) - sb.sum(axis=axis)) / n.sum(axis=axis)

    n = a["objects"]
    keep = n > 0
    data = (a[key][keep], b[key][keep], n[keep])
    estimate = float(diff(*data))
    res = stats.bootstrap(
        data,
        diff,
        paired=True,
        vectorized=True,
        n_resamples=N_RESAMPLES,
        confidence_level=0.95,
        method="BCa",
        **{_RNG_KEYWORD: np.random.default_rng(SEED)},
    )
    low, high = res.confidence_interval
    return 100 * estimate, 100 * float(low), 100 * float(high)


def _sums(group: pd.DataFrame) -> dict[str, np.ndarray]:
    """Per-frame sums of one method's objects in one setting."""
    keys = (group["sequence"] + "/" + group["frame"].astype(str)).to_numpy()
    return frame_sums(keys, group["iou"].to_numpy())


def _pairs(objects: pd.DataFrame, settings: bool):
    """(setting, method, minus, sums of method, sums of minus) of every pair to compare: the
    methods two by two within each setting, or (``settings``) each method's no-ground against
    its ground setting."""
    if settings:
        for method, group in objects.groupby("method", sort=False):
            by = {s: g for s, g in group.groupby("setting")}
            if set(by) != {"ground", "no-ground"}:
                raise SystemExit(f"{method}: --settings needs an evaluate run with --setting both")
            yield (
                "no-ground minus ground",
                method,
                method,
                _sums(by["no-ground"]),
                _sums(by["ground"]),
            )
        return
    for setting, group in objects.groupby("setting", sort=False):
        sums = {method: _sums(g) for method, g in group.groupby("method", sort=False)}
        for m1, m2 in itertools.combinations(sums, 2):
            yield setting, m1, m2, sums[m1], sums[m2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("evaluate", type=Path, help="an evaluate output folder")
    parser.add_argument(
        "--settings", action="store_true", help="each method's no-ground minus its ground score"
    )
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    objects = pd.read_csv(args.evaluate / "per_object.csv", dtype={"sequence": str})
    rows = []
    for setting, m1, m2, s1, s2 in _pairs(objects, args.settings):
        if not np.array_equal(s1["frame"], s2["frame"]) or not np.array_equal(
            s1["objects"], s2["objects"]
        ):
            raise SystemExit(f"{m1} and {m2} ({setting}) were not scored on the same objects")
        for score, key in (("iou_mu", "iou_sum"), ("p_mu", "p_sum")):
            est, low, high = paired(s1, s2, key)
            rows.append(
                {
                    "setting": setting,
                    "method": m1,
                    "minus": m2,
                    "score": score,
                    "difference": round(est, 2),
                    "low": round(low, 2),
                    "high": round(high, 2),
                    "significant": bool(low > 0 or high < 0),
                }
            )
    table = pd.DataFrame(rows)
    out = args.out or args.evaluate / "differences.csv"
    write_table(out, table)
    print(f"wrote {len(table)} paired differences -> {out}")


if __name__ == "__main__":
    main()
