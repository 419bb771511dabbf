"""Every method's quality per sensor on the synthetic streets (issue 21: the synthetic profiles).

For each sensor profile (``flic sample --sensor``) this writes the same street (seed 0) cast with
that sensor, runs ``flic evaluate`` on it (with the sample's ``sensor.toml`` as ``--config``),
then the paired differences (``scripts/paired_differences.py``), and gathers:

- ``OUT/<sensor>/``: the evaluate run (``table.csv``, ``per_setting.csv``, ... ) and
  ``differences.csv``;
- ``OUT/combined.csv``: one row per sensor, method and setting (IoU_mu with its interval, P_mu,
  objects, clusters, over- and under-segmented objects);
- ``OUT/geometry.csv``: each sensor's beam spacing and column step, and the ranges up to which
  FLIC's threshold (0.8 m) can link two rays ``k`` rows or columns apart on a surface facing the
  sensor (``t / (2 sin(k * step / 2))``), for the direct links (k = 1) and the Map Connections'
  smallest and largest steps (2 and 15);
- ``OUT/iou_per_sensor.png``: IoU_mu per method across the sensors (both settings);
- ``OUT/summary.csv`` (and printed): per sensor and setting, the paired differences the issue's
  targets ask about, where both methods ran: Bridge minus DBSCAN, and FLIC with 1 / 6 / 14 Map
  Connections minus FLIC 0 MC, with their 95 % intervals (``differences.csv``), and the over- /
  under-segmented objects of each.

Bridge against DBSCAN and what the Map Connections add, on 20 frames of every sensor (one
command; every method's sensor-dependent parameters derived from the data, as every run does)::

    python scripts/sensors_synthetic.py --frames 20 \
        --methods flic0,flic1,flic6,flic14,bridge,dbscan \
        --out results/sensors-synthetic/derived-20frames --work /tmp/flic-s20

Usage (from the repository root, ``../shared`` not needed)::

    python scripts/sensors_synthetic.py --frames 10 --out results/sensors-synthetic \\
        --work /tmp/flic-sensors
    python scripts/sensors_synthetic.py --gather-only --out results/sensors-synthetic

``--methods`` (default: the config's default methods) and ``--sensors`` choose a subset;
``--extra-config FILE`` is laid over every sensor's ``sensor.toml`` (a sweep's variants);
``--ground-remover NAME`` sets the ground setting's remover (default: the paper's).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import tomllib

from flic_cli.io.atomic import write_table
from flic_cli.plots import _pyplot, save_figure
from flic_cli.sample import SENSOR_PROFILES, write_sample

#: FLIC's default threshold, metres (flic_cli.methods.flic.Flic.threshold_m).
FLIC_T_M = 0.8


def _merged_config(sample_config: Path | None, extra: Path | None, dest: Path) -> Path | None:
    """The ``--config`` of one sensor: its ``sensor.toml`` with ``extra`` laid over it."""
    if extra is None:
        return sample_config
    import tomli_w

    data: dict = {}
    if sample_config is not None:
        data = tomllib.loads(sample_config.read_text())
    for key, value in tomllib.loads(extra.read_text()).items():
        if isinstance(value, dict) and isinstance(data.get(key), dict):
            data[key] = {**data[key], **value}
        else:
            data[key] = value
    dest.write_bytes(tomli_w.dumps(data).encode())
    return dest


def run_sensor(
    name: str,
    frames: int,
    work: Path,
    out: Path,
    methods: str | None,
    extra: Path | None,
    ground_remover: str | None = None,
    jobs: int = 1,
) -> None:
    """Write the sensor's street, evaluate it, and the paired differences, into ``out/<name>``."""
    paths = write_sample(work / name, frames=frames, seed=0, sensor=name)
    config = _merged_config(paths.config, extra, work / f"{name}.config.toml")
    cmd = ["flic", "evaluate", str(paths.kitti_root), "--setting", "both"]
    cmd += ["--frames", f"0:{frames}", "--out", str(out / name), "--jobs", str(jobs)]
    if config is not None:
        cmd += ["--config", str(config)]
    if methods:
        cmd += ["--methods", methods]
    if ground_remover:
        cmd += ["--ground-remover", ground_remover]
    print("$", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    script = Path(__file__).with_name("paired_differences.py")
    subprocess.run([sys.executable, str(script), str(out / name)], check=True)


def geometry() -> pd.DataFrame:
    """Per sensor: beam spacing (median and largest, degrees, between beams below +3 deg, the
    ones that see the street's objects), column step, and the ranges up to which FLIC's
    threshold links rays k rows or columns apart on a surface facing the sensor."""
    rows = []
    for name, p in SENSOR_PROFILES.items():
        elev = -p.pitch_deg
        street = elev <= 3.0
        spacing = np.diff(p.pitch_deg)[street[1:]]
        dv = float(np.median(spacing))
        dh = p.column_step_deg

        def reach(step_deg: float) -> float:
            return FLIC_T_M / (2.0 * np.sin(np.radians(step_deg) / 2.0))

        rows.append(
            {
                "sensor": name,
                "beams": p.beams,
                "columns": p.width,
                "beam_spacing_median_deg": round(dv, 3),
                "beam_spacing_max_deg": round(float(spacing.max()), 3),
                "column_step_deg": round(dh, 4),
                "flic_rows_1_m": round(reach(dv), 1),
                "flic_rows_2_m": round(reach(2 * dv), 1),
                "flic_rows_15_m": round(reach(15 * dv), 1),
                "flic_cols_1_m": round(reach(dh), 1),
                "flic_cols_15_m": round(reach(15 * dh), 1),
                "rows_per_1p8m_at_20m": round(np.degrees(np.arctan(1.8 / 20.0)) / dv, 1),
            }
        )
    return pd.DataFrame(rows)


def gather(out: Path) -> pd.DataFrame:
    """``combined.csv`` from every ``out/<sensor>/per_setting.csv`` and ``table.csv``."""
    parts = []
    for name, p in SENSOR_PROFILES.items():
        ps = out / name / "per_setting.csv"
        if not ps.is_file():
            continue
        df = pd.read_csv(ps)
        df.insert(0, "columns", p.width)
        df.insert(0, "beams", p.beams)
        df.insert(0, "sensor", name)
        table = pd.read_csv(out / name / "table.csv")
        for setting, col in (("no-ground", "iou_mu_no_ground"), ("ground", "iou_mu_ground")):
            if col not in table.columns:
                continue
            ci = dict(zip(table["method"], table[col], strict=True))
            sel = df["setting"] == setting
            df.loc[sel, "iou_mu_interval"] = df.loc[sel, "method"].map(ci)
        parts.append(df)
    if not parts:
        raise SystemExit(f"no per_setting.csv under {out}/<sensor>/")
    combined = pd.concat(parts, ignore_index=True)
    keep = ["sensor", "beams", "columns", "method", "setting", "frames", "objects", "iou_mu"]
    keep += ["iou_mu_interval", "p_mu", "p_0.50", "clusters_per_frame", "over_segmented"]
    keep += ["under_segmented"]
    return combined[[c for c in keep if c in combined.columns]]


#: (method, minus) pairs of ``summary.csv``.
SUMMARY_PAIRS = (("bridge", "dbscan"), ("flic1", "flic0"), ("flic6", "flic0"), ("flic14", "flic0"))


def summary(out: Path, combined: pd.DataFrame) -> pd.DataFrame:
    """Per sensor and setting, :data:`SUMMARY_PAIRS`' IoU_mu differences with their paired 95 %
    intervals (from ``out/<sensor>/differences.csv``; a pair stored the other way round is
    negated), and each method's over- / under-segmented objects."""
    rows = []
    for name in SENSOR_PROFILES:
        path = out / name / "differences.csv"
        if not path.is_file():
            continue
        diff = pd.read_csv(path)
        diff = diff[diff["score"] == "iou_mu"]
        for setting in ("no-ground", "ground"):
            d = diff[diff["setting"] == setting]
            seg = combined[(combined["sensor"] == name) & (combined["setting"] == setting)]
            seg = seg.set_index("method")
            for a, b in SUMMARY_PAIRS:
                hit = d[(d["method"] == a) & (d["minus"] == b)]
                sign = 1.0
                if hit.empty:
                    hit, sign = d[(d["method"] == b) & (d["minus"] == a)], -1.0
                if hit.empty:
                    continue
                r = hit.iloc[0]
                low, high = sorted((sign * r["low"], sign * r["high"]))
                row = {"sensor": name, "setting": setting, "method": a, "minus": b}
                row |= {"difference": round(sign * r["difference"], 2), "low": low, "high": high}
                row["significant"] = bool(r["significant"])
                for m, tag in ((a, "method"), (b, "minus")):
                    if m in seg.index and "over_segmented" in seg.columns:
                        row[f"{tag}_over_under"] = (
                            f"{int(seg.loc[m, 'over_segmented'])} / "
                            f"{int(seg.loc[m, 'under_segmented'])}"
                        )
                rows.append(row)
    return pd.DataFrame(rows)


def plot(combined: pd.DataFrame, path: Path) -> None:
    """IoU_mu per method (lines) across the sensors (x, fewest beams first), both settings."""
    plt = _pyplot()
    order = sorted(
        combined["sensor"].unique(),
        key=lambda s: (SENSOR_PROFILES[s].beams, SENSOR_PROFILES[s].width),
    )
    settings = [s for s in ("no-ground", "ground") if s in set(combined["setting"])]
    fig, axes = plt.subplots(1, len(settings), figsize=(6.5 * len(settings), 5.4), squeeze=False)
    labels = [f"{s}\n{SENSOR_PROFILES[s].beams}x{SENSOR_PROFILES[s].width}" for s in order]
    methods = list(dict.fromkeys(combined["method"]))
    colours = plt.get_cmap("tab20")
    for ax, setting in zip(axes[0], settings, strict=True):
        sub = combined[combined["setting"] == setting]
        for i, method in enumerate(methods):
            m = sub[sub["method"] == method].set_index("sensor").reindex(order)
            style = "-" if method in ("bridge", "dbscan") else "--"
            width = 2.6 if method in ("bridge", "dbscan") else 1.1
            colour = colours(i % 20)
            ax.plot(range(len(order)), m["iou_mu"], style, marker="o", lw=width, label=method,
                    color=colour)  # fmt: skip
        ax.set_xticks(range(len(order)), labels, fontsize=8)
        ax.set_ylabel("IoU_mu (%)")
        ax.set_title(f"synthetic street, {setting} setting")
        ax.grid(alpha=0.3)
    handles, names = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, names, fontsize=8, ncol=min(len(names), 6), loc="lower center")
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    save_figure(fig, path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument("--out", type=Path, default=Path("results/sensors-synthetic"))
    ap.add_argument("--work", type=Path, default=Path("/tmp/flic-sensors"))
    ap.add_argument("--sensors", default=",".join(SENSOR_PROFILES))
    ap.add_argument("--methods", default=None)
    ap.add_argument("--extra-config", type=Path, default=None)
    ap.add_argument("--ground-remover", default=None, help="of the ground setting (default: paper)")
    ap.add_argument("--jobs", type=int, default=1, help="evaluate's worker processes")
    ap.add_argument("--gather-only", action="store_true")
    args = ap.parse_args()
    if not args.gather_only:
        for name in args.sensors.split(","):
            if name not in SENSOR_PROFILES:
                raise SystemExit(f"unknown sensor {name!r}; one of {', '.join(SENSOR_PROFILES)}")
            run_sensor(
                name,
                args.frames,
                args.work,
                args.out,
                args.methods,
                args.extra_config,
                args.ground_remover,
                args.jobs,
            )
    args.out.mkdir(parents=True, exist_ok=True)
    write_table(args.out / "geometry.csv", geometry())
    combined = gather(args.out)
    write_table(args.out / "combined.csv", combined)
    plot(combined, args.out / "iou_per_sensor.png")
    table = summary(args.out, combined)
    if not table.empty:
        write_table(args.out / "summary.csv", table)
        print(table.to_string(index=False))
    print(f"wrote {args.out}/combined.csv, geometry.csv, iou_per_sensor.png, summary.csv")


if __name__ == "__main__":
    main()
