"""DBSCAN backends side by side: scikit-learn (reference) and the ``dbscan`` package.

For every labelled frame (the "No Ground" point set, as ``flic evaluate`` gives it to DBSCAN) both
backends run in the same process, interleaved, on one thread each (``PARLAY_NUM_THREADS=1`` is set
before the package loads). Written per frame: time of each, adjusted Rand index of the final labels
(clusters under ``min_size`` dropped), points whose final cluster differs (after matching each
package cluster to the scikit-learn cluster it overlaps most), and where the raw results differ:
core points (a neighbour at exactly ``eps``: scikit-learn counts ``<= eps``) and border points
given to another cluster or to none; for the core points that differ, how many neighbours within
``eps`` scikit-learn counts and how close the nearest of them lies to ``eps``. Also IoU_mu and P_mu
of both label sets (the protocol of docs/specification.md).

Usage: python scripts/dbscan_backends.py DATA OUT [--eps 0.5] [--min-samples 5] [--min-size 100]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("PARLAY_NUM_THREADS", "1")  # before the package starts its scheduler

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from sklearn.metrics import adjusted_rand_score  # noqa: E402
from sklearn.neighbors import NearestNeighbors  # noqa: E402
from tqdm import tqdm  # noqa: E402

from flic_cli.config import load_config  # noqa: E402
from flic_cli.io import open_dataset  # noqa: E402
from flic_cli.methods.base import drop_small  # noqa: E402
from flic_cli.methods.dbscan import raw_dbscan  # noqa: E402
from flic_cli.metrics import match_objects, summarize  # noqa: E402
from flic_cli.runs.pipeline import prepare  # noqa: E402
from flic_cli.runs.scoring import load_labelled_frame  # noqa: E402


def differing_points(ref: np.ndarray, other: np.ndarray) -> int:
    """Points whose cluster in ``other`` (mapped to the ``ref`` cluster it overlaps most) differs.

    Parameters
    ----------
    ref, other : (N,) int labels, 0 = none.
    """
    mapped = np.zeros_like(other)
    for k in np.unique(other[other > 0]):
        hits = ref[other == k]
        mapped[other == k] = np.bincount(hits).argmax()
    return int(np.count_nonzero(mapped != ref))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--eps", type=float, default=0.5)
    parser.add_argument("--min-samples", type=int, default=5)
    parser.add_argument("--min-size", type=int, default=100)
    args = parser.parse_args()
    cfg = load_config()
    ds = open_dataset(args.data)
    rows, ious = [], {"sklearn": [], "fastdbscan": []}
    for ref in tqdm(ds.refs(), unit="frame"):
        prep = prepare(load_labelled_frame(ds, ref), "no-ground", cfg.projection)
        pts = prep.points[prep.image.point_pixel >= 0]
        row = {"sequence": ref.sequence, "frame": ref.frame, "points": pts.shape[0]}
        raw, core, final = {}, {}, {}
        for backend in ("sklearn", "fastdbscan", "sklearn", "fastdbscan"):  # interleaved
            t0 = time.perf_counter()
            raw[backend], core[backend] = raw_dbscan(pts, args.eps, args.min_samples, backend)
            row[f"{backend}_s"] = min(row.get(f"{backend}_s", np.inf), time.perf_counter() - t0)
        for backend in raw:
            final[backend] = drop_small(raw[backend] + 1, args.min_size)
            labels = np.zeros(prep.points.shape[0], np.int32)
            labels[prep.image.point_pixel >= 0] = final[backend]
            ious[backend].append(match_objects(prep.labels, labels).iou)
        a, b = raw["sklearn"], raw["fastdbscan"]
        row["ari_final"] = adjusted_rand_score(final["sklearn"], final["fastdbscan"])
        row["ari_raw"] = adjusted_rand_score(a, b)
        row["differing_final"] = differing_points(final["sklearn"], final["fastdbscan"])
        row["differing_raw"] = differing_points(a + 1, b + 1)
        differs = np.flatnonzero(core["sklearn"] != core["fastdbscan"])
        row["core_differs"] = differs.size
        row["core_only_sklearn"] = int(np.count_nonzero(core["sklearn"][differs]))
        if differs.size:
            dist, _ = NearestNeighbors().fit(pts).radius_neighbors(pts[differs], args.eps)
            row["core_differs_at_min_samples"] = sum(d.size == args.min_samples for d in dist)
            row["core_differs_min_gap_to_eps"] = min(float(np.min(args.eps - d)) for d in dist)
        border = ~core["sklearn"] & ~core["fastdbscan"]
        row["border_noise_differs"] = int(np.count_nonzero(border & ((a < 0) != (b < 0))))
        both = border & (a >= 0) & (b >= 0)
        row["border_cluster_differs"] = differing_points(a[both] + 1, b[both] + 1)
        rows.append(row)
    df = pd.DataFrame(rows)
    df["speedup"] = df["sklearn_s"] / df["fastdbscan_s"]
    args.out.mkdir(parents=True, exist_ok=True)
    df.to_csv(args.out / "frames.csv", index=False, float_format="%.6g")
    gap = df["core_differs_min_gap_to_eps"] if "core_differs_min_gap_to_eps" in df else [np.nan]
    summary = {
        "frames": len(df),
        "median_sklearn_ms": 1e3 * df["sklearn_s"].median(),
        "median_fastdbscan_ms": 1e3 * df["fastdbscan_s"].median(),
        "median_speedup": df["speedup"].median(),
        "min_ari_final": df["ari_final"].min(),
        "frames_identical_final": int((df["differing_final"] == 0).sum()),
        "differing_final_total": int(df["differing_final"].sum()),
        "differing_raw_total": int(df["differing_raw"].sum()),
        "core_differs_total": int(df["core_differs"].sum()),
        "core_only_sklearn_total": int(df["core_only_sklearn"].sum()),
        # (absent when no core point differs on any frame)
        "core_differs_at_min_samples": int(
            df["core_differs_at_min_samples"].sum() if "core_differs_at_min_samples" in df else 0
        ),
        "core_differs_min_gap_to_eps_m": float(np.min(gap)),
        "border_noise_differs_total": int(df["border_noise_differs"].sum()),
        "border_cluster_differs_total": int(df["border_cluster_differs"].sum()),
        "points_total": int(df["points"].sum()),
    }
    for backend, values in ious.items():
        s = summarize(np.concatenate(values))
        summary[f"iou_mu_{backend}"] = 100 * s["iou_mu"]
        summary[f"p_mu_{backend}"] = 100 * s["p_mu"]
    pd.DataFrame([summary]).to_csv(args.out / "summary.csv", index=False, float_format="%.6g")
    for k, v in summary.items():
        print(f"{k:24s} {v:.6g}" if isinstance(v, float) else f"{k:24s} {v}")


if __name__ == "__main__":
    main()
