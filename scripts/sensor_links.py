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

Usage::

    python scripts/sensor_links.py --work /tmp/flic-sensors --frames 10 \\
        --out results/sensors-synthetic/vertical_links.csv
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", type=Path, default=Path("/tmp/flic-sensors"))
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument(
        "--out", type=Path, default=Path("results/sensors-synthetic/vertical_links.csv")
    )
    args = ap.parse_args()
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
