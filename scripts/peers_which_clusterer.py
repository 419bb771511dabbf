"""One table and one picture for "which clusterer?" from ``flic evaluate --semantics oracle``
runs: per method IoU_mu and P_mu (no-ground setting), IoU_mu (ground setting), PQ with oracle
semantics (19-class mean and thing-class mean), OSE / USE (no-ground setting), each with its 95 %
interval, and the median milliseconds per frame that run measured (no-ground setting, with the
other jobs of a shared machine: an indication).

Several runs may be given (e.g. the slow HDBSCAN on fewer frames): each method is taken from the
first run that has it, and the table says how many frames and objects its row rests on.

Usage: python scripts/peers_which_clusterer.py OUT RUN [RUN ...]
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

SCORES = (
    "iou_mu_no_ground",
    "p_mu",
    "iou_mu_ground",
    "pq_oracle",
    "pq_things_oracle",
    "ose",
    "use",
)
COLUMNS = (
    ["method", "frames", "objects"]
    + [f"{c}{end}" for c in SCORES for end in ("", "_low", "_high")]
    + ["ms_per_frame_median"]
)


def gather(runs: list[Path]) -> pd.DataFrame:
    rows = []
    seen: set[str] = set()
    for run in runs:
        table = pd.read_csv(run / "table.csv")
        frames = pd.read_csv(run / "per_frame.csv")
        for _, row in table.iterrows():
            if row["method"] in seen:
                continue
            seen.add(row["method"])
            sel = frames[(frames["method"] == row["method"]) & (frames["setting"] == "no-ground")]
            out = {c: row[c] for c in COLUMNS if c in row}
            out["frames"] = int(sel[["sequence", "frame"]].drop_duplicates().shape[0])
            out["ms_per_frame_median"] = round(1000 * float(sel["seconds"].median()), 3)
            rows.append(out)
    return pd.DataFrame(rows, columns=COLUMNS)


def plot(df: pd.DataFrame, path: Path) -> None:
    fig, (a, b) = plt.subplots(1, 2, figsize=(13, 5.5))
    for _, r in df.iterrows():
        x = r["ms_per_frame_median"]
        y, lo, hi = r["iou_mu_no_ground"], r["iou_mu_no_ground_low"], r["iou_mu_no_ground_high"]
        a.errorbar(x, y, yerr=[[y - lo], [hi - y]], fmt="o", capsize=3)
        a.annotate(f"{r['method']} ({r['frames']})", (x, r["iou_mu_no_ground"]), fontsize=7,
                   xytext=(3, 3), textcoords="offset points")  # fmt: skip
        xerr = [[r["ose"] - r["ose_low"]], [r["ose_high"] - r["ose"]]]
        yerr = [[r["use"] - r["use_low"]], [r["use_high"] - r["use"]]]
        b.errorbar(r["ose"], r["use"], xerr=xerr, yerr=yerr, fmt="o", capsize=3)
        b.annotate(r["method"], (r["ose"], r["use"]), fontsize=7, xytext=(3, 3),
                   textcoords="offset points")  # fmt: skip
    a.set_xscale("log")
    a.set_xlabel("median ms per frame (no-ground setting, shared 2-core machine; log)")
    a.set_ylabel("IoU_mu, no-ground setting (%), 95 % interval")
    a.set_title("quality against time (frames per method in brackets)")
    a.grid(True, which="both", alpha=0.3)
    b.set_xlabel("OSE per frame (lower: fewer objects split), 95 % interval")
    b.set_ylabel("USE per frame (lower: fewer objects merged)")
    b.set_title("over- against under-segmentation entropy (flic's objects)")
    b.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(out: Path, runs: list[Path]) -> None:
    out.mkdir(parents=True, exist_ok=True)
    df = gather(runs)
    df.to_csv(out / "which_clusterer.csv", index=False)
    plot(df, out / "which_clusterer.png")
    print(df.to_string(index=False))


if __name__ == "__main__":
    main(Path(sys.argv[1]), [Path(p) for p in sys.argv[2:]])
