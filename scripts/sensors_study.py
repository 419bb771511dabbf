"""Studies of the methods on other sensors: the synthetic street cast with each sensor profile
(``flic sample --sensor``), and what every run derives from the shared recordings
(results/sensors-synthetic/README.md cites each).

From the repository root, with the dev install (``../shared`` is needed by ``recordings`` only)::

    python scripts/sensors_study.py profiles --frames 10 --out results/sensors-synthetic \\
        --work /tmp/flic-sensors
    python scripts/sensors_study.py links --frames 10 --work /tmp/flic-sensors --out CSV [--mc CSV]
    python scripts/sensors_study.py ground-column --frames 20 --work /tmp/flic-s20 --out CSV
    python scripts/sensors_study.py mc-degrees --frames 20 --work /tmp/flic-s20 --out DIR
    python scripts/sensors_study.py recordings --out CSV

``python scripts/sensors_study.py STUDY --help`` says what each one measures and writes; the
exact commands of the committed files are step ``sensors-synthetic`` of
``scripts/make_results.sh``. ``WORK`` holds one street per sensor (``WORK/<sensor>/``, written by
``profiles`` and ``mc-degrees``, read by ``links`` and ``ground-column``).
"""

from __future__ import annotations

import argparse
import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import tomllib
from _studies import Studies, run_studies  # scripts/_studies.py

from flic_cli.classes import ground_mask, thing_mask
from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.labels import instance
from flic_cli.methods.flic import flic_labels
from flic_cli.metrics.ground import GroundCounts, ground_counts
from flic_cli.plots import _pyplot, save_figure
from flic_cli.runs.pipeline import prepare
from flic_cli.sample import DEFAULT_SENSOR, SENSOR_PROFILES, write_sample
from flic_cli.sensor_params import (
    RUN_JUMP_FLOOR,
    beams_of_dataset,
    column_run_jumps,
    for_beams,
    street_beam_gap_deg,
)

#: FLIC's default threshold, metres (flic_cli.methods.flic.Flic.threshold_m).
FLIC_T_M = 0.8


def evaluate(data: Path, frames: int, out: Path, extra: list[str], jobs: int) -> None:
    """``flic evaluate DATA --setting both`` on the first ``frames`` frames into ``out``, then the
    paired differences of its methods (``scripts/paired_differences.py``: ``differences.csv``)."""
    cmd = ["flic", "evaluate", str(data), "--setting", "both"]
    cmd += ["--frames", f"0:{frames}", "--out", str(out), "--jobs", str(jobs), *extra]
    print("$", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    script = Path(__file__).with_name("paired_differences.py")
    subprocess.run([sys.executable, str(script), str(out)], check=True)


def paired(d: pd.DataFrame, a: str, b: str) -> tuple[pd.Series, float] | None:
    """The row of ``differences.csv`` (one setting and score) for ``a`` minus ``b`` and its sign
    (-1 where the pair is stored the other way round); None where neither is there."""
    hit, sign = d[(d["method"] == a) & (d["minus"] == b)], 1.0
    if hit.empty:
        hit, sign = d[(d["method"] == b) & (d["minus"] == a)], -1.0
    return None if hit.empty else (hit.iloc[0], sign)


# ---- profiles ----------------------------------------------------------------------------------


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
    args: list[str] = []
    if config is not None:
        args += ["--config", str(config)]
    if methods:
        args += ["--methods", methods]
    if ground_remover:
        args += ["--ground-remover", ground_remover]
    evaluate(paths.kitti_root, frames, out / name, args, jobs)


def geometry() -> pd.DataFrame:
    """Per sensor: beam spacing (median and largest, degrees, between beams below +3 deg, the
    ones that see the street's objects), column step, and the ranges up to which FLIC's
    threshold links rays k rows or columns apart on a surface facing the sensor."""
    rows = []
    for name, p in SENSOR_PROFILES.items():
        elev = -p.pitch_deg
        street = elev <= 3.0
        spacing = np.diff(p.pitch_deg)[street[1:]]
        dv = street_beam_gap_deg(np.radians(elev))  # their median
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
                found = paired(d, a, b)
                if found is None:
                    continue
                r, sign = found
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


def profiles(args: argparse.Namespace) -> None:
    """Every method's quality per sensor on the synthetic streets.

    For each sensor profile (``flic sample --sensor``) this writes the same street (seed 0)
    cast with that sensor into ``WORK/<sensor>/``, runs ``flic evaluate`` on it (with the
    sample's ``sensor.toml`` as ``--config``), then the paired differences
    (``scripts/paired_differences.py``), and gathers:

    - ``OUT/<sensor>/``: the evaluate run (``table.csv``, ``per_setting.csv``, ... ) and
      ``differences.csv``;
    - ``OUT/combined.csv``: one row per sensor, method and setting (IoU_mu with its interval,
      P_mu, objects, clusters, over- and under-segmented objects);
    - ``OUT/geometry.csv``: each sensor's beam spacing and column step, and the ranges up to
      which FLIC's threshold (0.8 m) can link two rays ``k`` rows or columns apart on a surface
      facing the sensor (``t / (2 sin(k * step / 2))``), for the direct links (k = 1) and the
      Map Connections' smallest and largest steps (2 and 15);
    - ``OUT/iou_per_sensor.png``: IoU_mu per method across the sensors (both settings);
    - ``OUT/summary.csv`` (and printed): per sensor and setting, the paired differences the
      issue's targets ask about, where both methods ran: Bridge minus DBSCAN, and FLIC with 1 /
      6 / 14 Map Connections minus FLIC 0 MC, with their 95 % intervals (``differences.csv``),
      and the over- / under-segmented objects of each.

    ``--methods`` (default: the config's default methods) and ``--sensors`` choose a subset;
    ``--extra-config FILE`` is laid over every sensor's ``sensor.toml`` (a sweep's variants);
    ``--ground-remover NAME`` sets the ground setting's remover (default: the paper's);
    ``--gather-only`` rewrites the gathered files from the runs already in OUT.
    """
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


def _profiles_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--frames", type=int, default=10)
    p.add_argument("--out", type=Path, default=Path("results/sensors-synthetic"))
    p.add_argument("--work", type=Path, default=Path("/tmp/flic-sensors"))
    p.add_argument("--sensors", default=",".join(SENSOR_PROFILES))
    p.add_argument("--methods", default=None)
    p.add_argument("--extra-config", type=Path, default=None)
    p.add_argument("--ground-remover", default=None, help="of the ground setting (default: paper)")
    p.add_argument("--jobs", type=int, default=1, help="evaluate's worker processes")
    p.add_argument("--gather-only", action="store_true")


# ---- links -------------------------------------------------------------------------------------

BANDS_M = (0.0, 5.0, 10.0, 15.0, 20.0, 30.0, np.inf)


def bridge_t(d: np.ndarray) -> np.ndarray:
    """Bridge's link distance at range ``d`` with its defaults, metres."""
    return np.maximum(0.35, d * np.sin(np.radians(2.0)))


def pairs(image, inst: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Nearer range (m) and 3D distance (m) of every same-object pair ``k`` rows apart."""
    r = image.ranges.astype(np.float64)
    a, b = r[:-k], r[k:]
    ia, ib = inst[:-k], inst[k:]
    ok = (a > 0) & (b > 0) & (ia > 0) & (ia == ib)
    de = (image.elevation[:-k] - image.elevation[k:])[:, None]
    dist = np.sqrt(np.maximum(a * a + b * b - 2.0 * a * b * np.cos(de), 0.0))
    return np.minimum(a, b)[ok], dist[ok]


#: The Map Connection variants of :func:`mc_rows` (their ``maps`` from the shipped config).
MC_VARIANTS = ("flic1", "flic6", "flic14")


def _joined(image, comp: np.ndarray, maps: tuple) -> np.ndarray:
    """(K, 2) distinct pairs of different components (labels > 0) that ``maps`` link."""
    r = image.ranges.astype(np.float64)
    el = np.asarray(image.elevation, dtype=np.float64)
    h, w = r.shape
    found = []
    for m in maps:
        kr, kc = m[0], m[1]
        o_r, o_c = (m[2], m[3]) if len(m) == 4 else (0, 0)
        rows, cols = np.arange(o_r, h, kr), np.arange(o_c, w, kc)
        sub, csub = r[np.ix_(rows, cols)], comp[np.ix_(rows, cols)]
        cos_v = np.cos(el[rows][:-1] - el[rows][1:])[:, None]
        ce2 = np.cos(el[rows])[:, None] ** 2
        cos_h = ce2 * np.cos(kc * 2.0 * np.pi / w) + (1.0 - ce2)
        for a, b, ca, cb, cos_a in (
            (sub[:-1], sub[1:], csub[:-1], csub[1:], cos_v),
            (sub[:, :-1], sub[:, 1:], csub[:, :-1], csub[:, 1:], cos_h),
        ):
            d2 = a * a + b * b - 2.0 * cos_a * a * b
            ok = (ca > 0) & (cb > 0) & (ca != cb) & (d2 < FLIC_T_M**2)
            found.append(np.stack([np.minimum(ca, cb)[ok], np.maximum(ca, cb)[ok]], axis=1))
    pairs = np.concatenate(found) if found else np.empty((0, 2), dtype=np.int64)
    return np.unique(pairs, axis=0)


def mc_rows(name: str, folder: Path, frames: int) -> list[dict]:
    """What each MC variant joins between FLIC 0 MC's components on one sensor (``links``)."""
    toml = folder / "sensor.toml"
    cfg = load_config(toml if name != DEFAULT_SENSOR else None)
    maps = {v: cfg.methods[v].method.maps for v in MC_VARIANTS}
    ds = open_dataset(folder / "semantickitti", frames=(0, frames))
    kinds = ("completes", "merges_objects", "object_background", "background")
    acc = {v: {k: [0, 0] for k in kinds} for v in MC_VARIANTS}
    refs = ds.refs()
    distances = []  # every object's median range (objects of at least 100 points)
    for ref in refs:
        prep = prepare(ds.load(ref), "no-ground", cfg.projection)
        image = prep.image
        things = thing_mask(prep.labels)
        ids, inv, n_pts = np.unique(
            instance(prep.labels[things]), return_inverse=True, return_counts=True
        )
        rng = np.linalg.norm(prep.points[things], axis=1)
        distances += [float(np.median(rng[inv == i])) for i in np.flatnonzero(n_pts >= 100)]
        comp = flic_labels(image.ranges, image.elevation, FLIC_T_M, 1, ())
        obj = np.zeros(image.ranges.size, dtype=np.int64)
        obj[image.point_pixel[things]] = instance(prep.labels[things])
        flat = comp.reshape(-1)
        valid = flat > 0
        # every component's majority object and its size in pixels
        pairs_df = pd.DataFrame({"c": flat[valid], "o": obj[valid]})
        counts = pairs_df.value_counts().reset_index(name="n")
        major = counts.sort_values("n", ascending=False).drop_duplicates("c").set_index("c")["o"]
        size = pairs_df["c"].value_counts()
        for v in MC_VARIANTS:
            joined = _joined(image, comp, maps[v])
            if joined.size == 0:
                continue
            oa = major.reindex(joined[:, 0]).to_numpy()
            ob = major.reindex(joined[:, 1]).to_numpy()
            moved = np.minimum(
                size.reindex(joined[:, 0]).to_numpy(), size.reindex(joined[:, 1]).to_numpy()
            )
            kind = np.where(
                (oa == ob) & (oa > 0),
                0,
                np.where((oa > 0) & (ob > 0), 1, np.where((oa > 0) | (ob > 0), 2, 3)),
            )
            for i, k in enumerate(kinds):
                acc[v][k][0] += int(np.count_nonzero(kind == i))
                acc[v][k][1] += int(moved[kind == i].sum())
    out = []
    n = max(len(refs), 1)
    profile = SENSOR_PROFILES[name]
    gap = street_beam_gap_deg(-np.radians(profile.pitch_deg))
    d = float(np.median(distances)) if distances else float("nan")
    geometry = {
        "objects": len(distances),
        "median_object_range_m": round(d, 1),
        "beam_gap_deg": round(gap, 3),
        # two adjacent beams / columns on a surface facing the sensor at that range
        "row_gap_at_median_m": round(2.0 * d * np.sin(np.radians(gap) / 2.0), 3),
        "column_gap_at_median_m": round(
            2.0 * d * np.sin(np.radians(profile.column_step_deg) / 2.0), 3
        ),
    }
    for v in MC_VARIANTS:
        row = {"sensor": name, "variant": v, "frames": len(refs), **geometry}
        for k in kinds:
            row[f"{k}_per_frame"] = round(acc[v][k][0] / n, 2)
            row[f"{k}_points_per_frame"] = round(acc[v][k][1] / n, 1)
        out.append(row)
    return out


def links(args: argparse.Namespace) -> None:
    """Why methods break on sparse sensors: can two rows of one object be linked at all?

    For every sensor profile's street in WORK (written by ``profiles``), every pair of valid
    pixels of one column ``k`` rows apart (k = 1: adjacent beams; k = 2: FLIC's smallest Map
    Connection) that belong to the same ground-truth thing object is measured: the 3D distance
    between the two measurements, by range band of the nearer one. The table gives, per sensor,
    band and k, the pairs and the share of them that each method's link test could join:

    - FLIC: distance < 0.8 m (its default ``threshold_m``);
    - Bridge: distance < max(0.35 m, d sin 2 deg) (its defaults ``threshold_m``, ``gamma_deg``);
    - DBSCAN: distance < 0.5 m (``eps_m``; DBSCAN links any two points within eps, not only
      pixel neighbours, so this is a lower bound of what it can join).

    With ``--mc OUT``, also what FLIC's Map Connections join that its direct links did not: on
    the no-ground setting's image (ground removed by label, as the no-ground IoU_mu is scored),
    FLIC 0 MC's connected components (0.8 m, before its 100-point minimum), then every link of
    the 1 / 6 / 14 MC variants' maps (map reading: the sub-image of every k-th row and column,
    its 4-neighbours, the same 0.8 m test) between two different components. Each component
    takes the ground-truth object most of its pixels belong to (0: none, a stuff class), and
    each joined pair of components is: ``completes`` (the same object), ``merges_objects`` (two
    different objects), ``object_background`` (an object and a non-object cluster: vegetation, a
    fence, a wall, a pole), or ``background``; per frame, with the points of the smaller
    component of each pair (what the join moves). Chains through several joins are not followed.
    """
    if args.mc is not None:
        mc = []
        for name in SENSOR_PROFILES:
            mc += mc_rows(name, args.work / name, args.frames)
            print(pd.DataFrame(mc[-3:]).to_string(index=False), flush=True)
        write_table(args.mc, pd.DataFrame(mc))
        print(f"wrote {args.mc}")
    rows = []
    for name in SENSOR_PROFILES:
        folder = args.work / name
        toml = folder / "sensor.toml"
        cfg = load_config(toml if name != DEFAULT_SENSOR else None)
        ds = open_dataset(folder / "semantickitti", frames=(0, args.frames))
        acc: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {1: [], 2: []}
        for ref in ds.refs():
            frame = ds.load(ref)
            image = cfg.projection(frame.points)
            inst = np.zeros(image.ranges.size, dtype=np.int64)
            inst[image.point_pixel] = instance(frame.labels)  # one point per pixel (the sample)
            inst = inst.reshape(image.ranges.shape)
            for k in acc:
                acc[k].append(pairs(image, inst, k))
        for k, parts in acc.items():
            near = np.concatenate([p[0] for p in parts])
            dist = np.concatenate([p[1] for p in parts])
            band = np.digitize(near, BANDS_M[1:-1])
            for i in range(len(BANDS_M) - 1):
                sel = band == i
                n = int(sel.sum())
                if n == 0:
                    continue
                d, rng = dist[sel], near[sel]
                rows.append(
                    {
                        "sensor": name,
                        "rows_apart": k,
                        "band_m": f"{BANDS_M[i]:g}-{BANDS_M[i + 1]:g}".replace("-inf", "+"),
                        "pairs": n,
                        "median_distance_m": round(float(np.median(d)), 3),
                        "flic_0.8m_pct": round(100.0 * float(np.mean(d < 0.8)), 1),
                        "bridge_pct": round(100.0 * float(np.mean(d < bridge_t(rng))), 1),
                        "dbscan_0.5m_pct": round(100.0 * float(np.mean(d < 0.5)), 1),
                    }
                )
        print(name, "done", flush=True)
    write_table(args.out, pd.DataFrame(rows))
    print(f"wrote {args.out}")


def _links_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--work", type=Path, default=Path("/tmp/flic-sensors"))
    p.add_argument("--frames", type=int, default=10)
    p.add_argument("--out", type=Path, default=Path("results/sensors-synthetic/vertical_links.csv"))
    p.add_argument("--mc", type=Path, default=None, help="also write the MC joins here")


# ---- ground-column -----------------------------------------------------------------------------


def ground_column_rows(name: str, frames: int, work: Path) -> list[dict]:
    """Column's scores on one sensor's street, before and after."""
    folder = work / name
    if not (folder / "semantickitti").is_dir():
        write_sample(folder, frames=frames, seed=0, sensor=name)
    paths_config = folder / "sensor.toml"
    config = load_config(paths_config if paths_config.is_file() else None)
    after = config.remover("column")
    variants = {"before": dataclasses.replace(after, run_jump=RUN_JUMP_FLOOR), "after": after}
    ds = open_dataset(folder / "semantickitti", None, (0, frames))
    refs = ds.refs()[:frames]
    counts = {k: GroundCounts() for k in variants}
    bottom = {k: [0, 0] for k in variants}
    changed_rows = 0
    for ref in refs:
        prep = prepare(ds.load(ref), "ground", config.projection)
        w = prep.image.shape[1]
        rows = np.where(prep.image.point_pixel >= 0, prep.image.point_pixel // w, -1)
        low = rows >= prep.image.shape[0] - 2
        changed_rows = int(np.count_nonzero(after.run_jumps(prep.image) != RUN_JUMP_FLOOR))
        truth = ground_mask(prep.labels)
        for key, remover in variants.items():
            taken = remover.extract(prep.image, prep.points).on_ground
            counts[key] = counts[key] + ground_counts(prep.labels, taken)
            bottom[key][0] += int(np.count_nonzero(taken & truth & low))
            bottom[key][1] += int(np.count_nonzero(truth & low))
    out = []
    for key in variants:
        c = counts[key]
        out.append(
            {
                "sensor": name,
                "beams": SENSOR_PROFILES[name].beams,
                "columns": SENSOR_PROFILES[name].width,
                "column": key,
                "frames": len(refs),
                "rows_with_derived_limit": changed_rows,
                "precision": round(100 * c.precision, 2),
                "recall": round(100 * c.recall, 2),
                "f1": round(100 * c.f1, 2),
                "thing_points_removed": round(100 * c.things_removed_share, 2),
                "bottom_two_rows_recall": round(100 * bottom[key][0] / max(bottom[key][1], 1), 2),
            }
        )
    return out


def ground_column(args: argparse.Namespace) -> None:
    """The column ground remover per sensor profile: run limits from the beam table, and fixed.

    For every sensor profile (``flic sample --sensor``, the street of seed 0, in WORK) and every
    frame, the ground setting's image and points, and column's decision twice: ``before``, the
    fixed depth-jump limit of its confirming runs (``run_jump = 0.3`` on every row) and
    ``after``, the per-row limits from the beam table
    (:func:`flic_cli.sensor_params.column_run_jumps`, the default). Scored as ``flic evaluate``
    scores a remover (:func:`flic_cli.metrics.ground.ground_counts`: points of the ground
    classes, pooled over the frames): precision, recall, F1, and the share of thing-object points
    taken. Also the ground recall of the bottom two rows, where the VLP-32C's beams are farthest
    apart.
    """
    rows = []
    for name in args.sensors.split(","):
        rows += ground_column_rows(name, args.frames, args.work)
        print(pd.DataFrame(rows[-2:]).to_string(index=False), flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_table(args.out, pd.DataFrame(rows))
    print(f"wrote {args.out}")


def _ground_column_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--frames", type=int, default=20)
    p.add_argument("--work", type=Path, default=Path("/tmp/flic-s20"))
    p.add_argument("--sensors", default=",".join(SENSOR_PROFILES))
    p.add_argument(
        "--out", type=Path, default=Path("results/sensors-synthetic/ground-column/before_after.csv")
    )


# ---- mc-degrees --------------------------------------------------------------------------------

REFERENCE = DEFAULT_SENSOR  # the HDL-64E, where the steps were chosen


def _angles(name: str) -> tuple[float, float]:
    p = SENSOR_PROFILES[name]
    return street_beam_gap_deg(-np.radians(p.pitch_deg)), p.column_step_deg


def degree_maps(name: str) -> list[list[int]]:
    """flic14's maps with their steps read in degrees of the reference sensor (module doc)."""
    g0, c0 = _angles(REFERENCE)
    g, c = _angles(name)
    out: list[list[int]] = []
    for m in load_config().methods["flic14"].method.maps:
        step = [max(1, round(m[0] * g0 / g)), max(1, round(m[1] * c0 / c))]
        if step != [1, 1] and step not in out:
            out.append(step)
    return out


#: (method, minus) pairs of ``mc-degrees``' ``summary.csv``.
MC_PAIRS = (("flic14", "flic0"), ("flic14deg", "flic0"), ("flic14deg", "flic14"))


def mc_summary(out: Path, name: str) -> list[dict]:
    """:data:`MC_PAIRS`' IoU_mu differences of one sensor's run (``out/<name>/differences.csv``)."""
    diff = pd.read_csv(out / name / "differences.csv")
    diff = diff[diff["score"] == "iou_mu"]
    maps = str(degree_maps(name))
    rows = []
    for setting in ("no-ground", "ground"):
        d = diff[diff["setting"] == setting]
        for a, b in MC_PAIRS:
            found = paired(d, a, b)
            if found is None:
                raise SystemExit(f"{out / name / 'differences.csv'}: no {a} - {b} ({setting})")
            r, sign = found
            low, high = sorted((sign * r["low"], sign * r["high"]))
            rows.append(
                {
                    "sensor": name,
                    "setting": setting,
                    "method": a,
                    "minus": b,
                    "difference": round(sign * r["difference"], 2),
                    "low": low,
                    "high": high,
                    "significant": bool(r["significant"]),
                    "flic14deg_maps": maps,
                }
            )
    return rows


def mc_degrees(args: argparse.Namespace) -> None:
    """Should FLIC's Map Connection steps follow the sensor's angular resolution?

    FLIC's 14 MCs have steps ``(k, k)``, k = 2..15, in pixels, chosen on the HDL-64E (beams
    0.37 deg apart at the street, columns 0.176 deg). Read in degrees, the same MCs on another
    sensor would have steps ``(round(k * 0.37 / g), round(k * 0.176 / c))`` for its beam gap
    ``g`` and column step ``c`` (at least 1; a step (1, 1) is the direct links and is left out;
    repeated steps once). For every profile this writes that variant (``flic14deg``) into a
    config beside the sensor's ``sensor.toml``, runs ``flic evaluate`` on FLIC 0 MC, FLIC 14 MC
    and ``flic14deg`` (both settings) and the paired differences, into ``OUT/<sensor>/``, and
    gathers ``OUT/summary.csv``: flic14 - flic0, flic14deg - flic0 and flic14deg - flic14 per
    sensor and setting, with the maps (``--gather-only``: from the runs already in OUT).
    """
    rows = []
    for name in args.sensors.split(","):
        if args.gather_only:
            if (args.out / name / "differences.csv").is_file():
                rows += mc_summary(args.out, name)
            continue
        folder = args.work / name
        if not (folder / "semantickitti").is_dir():
            write_sample(folder, frames=args.frames, seed=0, sensor=name)
        maps = degree_maps(name)
        toml = folder / "sensor.toml"
        text = toml.read_text() if toml.is_file() else ""
        text += f'\n[methods.flic14deg]\nlike = "flic0"\nmaps = {maps}\n'
        config = args.work / f"{name}.mc-degrees.toml"
        config.write_text(text)
        extra = ["--config", str(config), "--methods", "flic0,flic14,flic14deg"]
        evaluate(folder / "semantickitti", args.frames, args.out / name, extra, args.jobs)
        rows += mc_summary(args.out, name)
        print(pd.DataFrame(rows[-6:]).to_string(index=False), flush=True)
    write_table(args.out / "summary.csv", pd.DataFrame(rows))
    print(f"wrote {args.out}/summary.csv")


def _mc_degrees_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--frames", type=int, default=20)
    p.add_argument("--work", type=Path, default=Path("/tmp/flic-s20"))
    p.add_argument("--out", type=Path, default=Path("results/sensors-synthetic/mc-degrees"))
    p.add_argument("--sensors", default=",".join(SENSOR_PROFILES))
    p.add_argument("--jobs", type=int, default=1)
    p.add_argument("--gather-only", action="store_true", help="only write summary.csv")


# ---- recordings --------------------------------------------------------------------------------

RECORDINGS = (
    "semantickitti/sequences/00",
    "sensors/ouster/OS-2-128-U1_v2.3.0_1024x10.pcap",
    "sensors/ouster/OS-1-64_1024x10_fw20.pcap",
    "sensors/ouster/512x10_raw.bag",
    "sensors/velodyne/vlp16_velodyne_example.pcap",
    "sensors/velodyne/nebula_vlp16/1673400472138016708.pcd",
    "sensors/pcd/robosense_helios16p_1691031766781547066.pcd",
    "sensors/nuscenes/n015-2018-07-24-11-22-45+0800__LIDAR_TOP__1532402927647951.pcd.bin",
)


def recordings(args: argparse.Namespace) -> None:
    """What every run derives from each shared recording's sensor (needs ../shared/data).

    The beam table the runs read (:func:`flic_cli.sensor_params.beams_of_dataset`), the Bridge
    parameters
    :func:`flic_cli.sensor_params.for_dataset` gives every Bridge variant, and the column
    remover's run limits above 0.3 (:func:`flic_cli.sensor_params.column_run_jumps`).
    """
    config = load_config()
    rows = []
    for rel in RECORDINGS:
        path = args.shared / rel
        if not path.exists():
            print(f"missing: {path}")
            continue
        ds = open_dataset(path, None, (0, 1))
        beams = beams_of_dataset(ds, ds.refs(), config.projection)
        derived = for_beams(config, beams)[1].get("bridge", {})
        jumps = column_run_jumps(beams.elevation)
        raised = jumps > RUN_JUMP_FLOOR
        try:
            gap = round(street_beam_gap_deg(beams.elevation), 3)
        except ValueError:
            gap = float("nan")
        rows.append(
            {
                "recording": Path(rel).name,
                "format": ds.format,
                "beams": beams.elevation.size,
                "columns": beams.columns,
                "beam_table_from": beams.source,
                "street_beam_gap_deg": gap,
                "bridge_gamma_deg": derived.get("gamma_deg", "default (2.0)"),
                "bridge_threshold_m": derived.get("threshold_m", "default (0.35)"),
                "column_rows_above_0.3": int(np.count_nonzero(raised)),
                "column_largest_limit": round(float(jumps.max()), 3),
            }
        )
        print(rows[-1], flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_table(args.out, pd.DataFrame(rows))
    print(f"wrote {args.out}")


def _recordings_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--shared", type=Path, default=Path("../shared/data"))
    p.add_argument(
        "--out",
        type=Path,
        default=Path("results/sensors-synthetic/derived-recordings/recordings.csv"),
    )


# ---- the command line --------------------------------------------------------------------------

STUDIES: Studies = {
    "profiles": (profiles, _profiles_arguments),
    "links": (links, _links_arguments),
    "ground-column": (ground_column, _ground_column_arguments),
    "mc-degrees": (mc_degrees, _mc_degrees_arguments),
    "recordings": (recordings, _recordings_arguments),
}


def main(argv: list[str] | None = None) -> None:
    run_studies(__doc__, STUDIES, argv)


if __name__ == "__main__":
    main()
