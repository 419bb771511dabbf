"""Which differences between methods in an evaluate run are significant: paired bootstrap.

Two methods are scored on the same objects of the same frames, so their difference is far less
uncertain than their two intervals side by side suggest. For every pair of methods and each
setting, the difference of IoU_mu (and of P_mu) is resampled by frames (both methods' per-frame
sums drawn together; :func:`flic_cli.metrics.intervals.frame_sums`) with scipy.stats.bootstrap
(BCa, 9999 resamples, seed 0); a difference is significant when its 95 % interval excludes 0.

Usage: python scripts/paired_differences.py results/evaluate     (writes differences.csv there)
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("evaluate", type=Path, help="an evaluate output folder")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    objects = pd.read_csv(args.evaluate / "per_object.csv", dtype={"sequence": str})
    rows = []
    for setting, group in objects.groupby("setting", sort=False):
        sums = {}
        for method, g in group.groupby("method", sort=False):
            keys = (g["sequence"] + "/" + g["frame"].astype(str)).to_numpy()
            sums[method] = frame_sums(keys, g["iou"].to_numpy())
        for m1, m2 in itertools.combinations(sums, 2):
            if not np.array_equal(sums[m1]["frame"], sums[m2]["frame"]):
                raise SystemExit(f"{m1} and {m2} were not scored on the same frames")
            for score, key in (("iou_mu", "iou_sum"), ("p_mu", "p_sum")):
                est, low, high = paired(sums[m1], sums[m2], key)
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
