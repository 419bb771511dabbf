"""One table and one picture for "which clusterer?" (issue 23), from ``flic evaluate
--semantics oracle`` runs in the no-ground and the ground setting and a ``flic benchmark`` run:
per method and setting IoU_mu, P_mu, PQ with oracle semantics (19-class mean and thing-class
mean), OSE / USE, each with its 95 % interval, and the median ms per frame that the benchmark
measured (and, for reference, the evaluate run's own).

Several runs may be given per setting (e.g. the slow HDBSCAN on fewer frames): each method is
taken from the first run that has it, and the table says how many frames and objects its row
rests on. scripts/peers_which_clusterer.sh makes the runs.

Usage::

    python scripts/peers_which_clusterer.py OUT --benchmark BENCH \
        --no-ground RUN [RUN ...] --ground RUN [RUN ...]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

SCORES = ("iou_mu", "p_mu", "pq_oracle", "pq_things_oracle", "ose", "use")
COLUMNS = (
    ["method", "setting", "frames", "objects"]
    + [f"{c}{end}" for c in SCORES for end in ("", "_low", "_high")]
    + ["ms_benchmark_median", "benchmark_frames", "ms_evaluate_median"]
)


def gather(setting: str, runs: list[Path], bench: pd.DataFrame) -> list[dict]:
    key = "iou_mu_" + setting.replace("-", "_")
    rows, seen = [], set()
    for run in runs:
        if not (run / "table.csv").is_file():
            print(f"left out: {run} (no table.csv: the run did not finish)")
            continue
        table = pd.read_csv(run / "table.csv")
        frames = pd.read_csv(run / "per_frame.csv")
        for _, row in table.iterrows():
            if row["method"] in seen:
                continue
            seen.add(row["method"])
            sel = frames[(frames["method"] == row["method"]) & (frames["setting"] == setting)]
            out = {"method": row["method"], "setting": setting, "objects": row["objects"]}
            for end in ("", "_low", "_high"):
                out[f"iou_mu{end}"] = row[f"{key}{end}"]
                for c in SCORES[1:]:
                    out[f"{c}{end}"] = row[f"{c}{end}"]
            out["frames"] = int(sel[["sequence", "frame"]].drop_duplicates().shape[0])
            out["ms_evaluate_median"] = round(1000 * float(sel["seconds"].median()), 3)
            if row["method"] in bench.index:
                out["ms_benchmark_median"] = round(float(bench.loc[row["method"], "median_ms"]), 3)
                out["benchmark_frames"] = int(bench.loc[row["method"], "frames"])
            rows.append(out)
    return rows


def plot(df: pd.DataFrame, path: Path) -> None:
    settings = list(dict.fromkeys(df["setting"]))
    fig, axes = plt.subplots(len(settings), 2, figsize=(14, 5.5 * len(settings)), squeeze=False)
    for (a, b), setting in zip(axes, settings, strict=True):
        for _, r in df[df["setting"] == setting].iterrows():
            x = r["ms_benchmark_median"]
            if pd.isna(x):
                x = r["ms_evaluate_median"]
            y, lo, hi = r["iou_mu"], r["iou_mu_low"], r["iou_mu_high"]
            a.errorbar(x, y, yerr=[[y - lo], [hi - y]], fmt="o", capsize=3)
            a.annotate(f"{r['method']} ({r['frames']})", (x, y), fontsize=7, xytext=(3, 3),
                       textcoords="offset points")  # fmt: skip
            xerr = [[r["ose"] - r["ose_low"]], [r["ose_high"] - r["ose"]]]
            yerr = [[r["use"] - r["use_low"]], [r["use_high"] - r["use"]]]
            b.errorbar(r["ose"], r["use"], xerr=xerr, yerr=yerr, fmt="o", capsize=3)
            b.annotate(r["method"], (r["ose"], r["use"]), fontsize=7, xytext=(3, 3),
                       textcoords="offset points")  # fmt: skip
        a.set_xscale("log")
        a.set_xlabel("median ms per frame: flic benchmark (ground setting, column) where run, "
                     "else the evaluate run's; log")  # fmt: skip
        a.set_ylabel(f"IoU_mu, {setting} setting (%), 95 % interval")
        a.set_title(f"{setting}: quality against time (frames per method in brackets)")
        a.grid(True, which="both", alpha=0.3)
        b.set_xlabel("OSE per frame (lower: fewer objects split), 95 % interval")
        b.set_ylabel("USE per frame (lower: fewer objects merged)")
        b.set_title(f"{setting}: over- against under-segmentation entropy (flic's objects)")
        b.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--benchmark", type=Path, help="a flic benchmark output (else no ms column)")
    ap.add_argument("--no-ground", type=Path, nargs="+", default=[], help="evaluate outputs")
    ap.add_argument("--ground", type=Path, nargs="+", default=[], help="evaluate outputs")
    args = ap.parse_args()
    summary = args.benchmark / "summary.csv" if args.benchmark else None
    if summary is not None and summary.is_file():
        bench = pd.read_csv(summary).set_index("method")
    else:
        print("no benchmark summary: the picture uses the evaluate runs' own times")
        bench = pd.DataFrame(columns=["median_ms", "frames"])
    rows = gather("no-ground", args.no_ground, bench) + gather("ground", args.ground, bench)
    df = pd.DataFrame(rows, columns=COLUMNS)
    args.out.mkdir(parents=True, exist_ok=True)
    df.to_csv(args.out / "which_clusterer.csv", index=False)
    plot(df, args.out / "which_clusterer.png")
    print(df.to_string(index=False))


if __name__ == "__main__":
    main()
