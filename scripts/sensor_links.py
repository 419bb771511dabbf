"""Why methods break on sparse sensors: can two rows of one object be linked at all?

For every sensor profile's street (written by ``scripts/sensors_synthetic.py`` into WORK), every
pair of valid pixels of one column ``k`` rows apart (k = 1: adjacent beams; k = 2: FLIC's smallest
Map Connection) that belong to the same ground-truth thing object is measured: the 3D distance
between the two measurements, by range band of the nearer one. The table gives, per sensor, band
and k, the pairs and the share of them that each method's link test could join:

- FLIC: distance < 0.8 m (its default ``threshold_m``);
- Bridge: distance < max(0.35 m, d sin 2 deg) (its defaults ``threshold_m``, ``gamma_deg``);
- DBSCAN: distance < 0.5 m (``eps_m``; DBSCAN links any two points within eps, not only pixel
  neighbours, so this is a lower bound of what it can join).

With ``--mc OUT``, also what FLIC's Map Connections join that its direct links did not: on the
no-ground setting's image (ground removed by label, as the no-ground IoU_mu is scored), FLIC 0
MC's connected components (0.8 m, before its 100-point minimum), then every link of the 1 / 6 /
14 MC variants' maps (map reading: the sub-image of every k-th row and column, its 4-neighbours,
the same 0.8 m test) between two different components. Each component takes the ground-truth
object most of its pixels belong to (0: none, a stuff class), and each joined pair of components
is: ``completes`` (the same object), ``merges_objects`` (two different objects),
``object_background`` (an object and a non-object cluster: vegetation, a fence, a wall, a pole),
or ``background``; per frame, with the points of the smaller component of each pair (what the
join moves). Chains through several joins are not followed.

Usage::

    python scripts/sensor_links.py --work /tmp/flic-sensors --frames 10 \\
        --out results/sensors-synthetic/vertical_links.csv
    python scripts/sensor_links.py --work /tmp/flic-s20 --frames 20 \\
        --out /tmp/vertical_links.csv --mc results/sensors-synthetic/mc_links.csv
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.labels import instance
from flic_cli.sample import DEFAULT_SENSOR, SENSOR_PROFILES
from flic_cli.sensor_params import street_beam_gap_deg

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
#: FLIC's threshold, metres (``Flic.threshold_m``).
FLIC_T_M = 0.8


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
    """What each MC variant joins between FLIC 0 MC's components on one sensor (module doc)."""
    from flic_cli.classes import thing_mask
    from flic_cli.methods.flic import flic_labels
    from flic_cli.runs.pipeline import prepare

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", type=Path, default=Path("/tmp/flic-sensors"))
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument(
        "--out", type=Path, default=Path("results/sensors-synthetic/vertical_links.csv")
    )
    ap.add_argument("--mc", type=Path, default=None, help="also write the MC joins here")
    args = ap.parse_args()
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


if __name__ == "__main__":
    main()
