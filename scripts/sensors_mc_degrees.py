"""Should FLIC's Map Connection steps follow the sensor's angular resolution? A test on the
synthetic profiles (issue 21: methods on other sensors).

FLIC's 14 MCs have steps ``(k, k)``, k = 2..15, in pixels, chosen on the HDL-64E (beams 0.37 deg
apart at the street, columns 0.176 deg). Read in degrees, the same MCs on another sensor would
have steps ``(round(k * 0.37 / g), round(k * 0.176 / c))`` for its beam gap ``g`` and column step
``c`` (at least 1; a step (1, 1) is the direct links and is left out; repeated steps once). For
every profile this writes that variant (``flic14deg``) into a config beside the sensor's
``sensor.toml``, runs ``flic evaluate`` on FLIC 0 MC, FLIC 14 MC and ``flic14deg`` (20 frames,
both settings) and the paired differences, into ``OUT/<sensor>/``, and gathers
``OUT/summary.csv``: flic14 - flic0, flic14deg - flic0 and flic14deg - flic14 per sensor and
setting, with the maps (``--gather-only``: from the runs already in OUT).

Usage (from the repository root; ``../shared`` not needed)::

    python scripts/sensors_mc_degrees.py --frames 20 --work /tmp/flic-s20 \\
        --out results/sensors-synthetic/mc-degrees
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.config import load_config
from flic_cli.io.atomic import write_table
from flic_cli.sample import DEFAULT_SENSOR, SENSOR_PROFILES, write_sample
from flic_cli.sensor_params import street_beam_gap_deg

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


PAIRS = (("flic14", "flic0"), ("flic14deg", "flic0"), ("flic14deg", "flic14"))


def summarise(out: Path, name: str) -> list[dict]:
    """:data:`PAIRS`' IoU_mu differences of one sensor's run (``out/<name>/differences.csv``)."""
    diff = pd.read_csv(out / name / "differences.csv")
    diff = diff[diff["score"] == "iou_mu"]
    maps = str(degree_maps(name))
    rows = []
    for setting in ("no-ground", "ground"):
        d = diff[diff["setting"] == setting]
        for a, b in PAIRS:
            hit, sign = d[(d["method"] == a) & (d["minus"] == b)], 1.0
            if hit.empty:
                hit, sign = d[(d["method"] == b) & (d["minus"] == a)], -1.0
            r = hit.iloc[0]
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--work", type=Path, default=Path("/tmp/flic-s20"))
    ap.add_argument("--out", type=Path, default=Path("results/sensors-synthetic/mc-degrees"))
    ap.add_argument("--sensors", default=",".join(SENSOR_PROFILES))
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--gather-only", action="store_true", help="only write summary.csv")
    args = ap.parse_args()
    rows = []
    for name in args.sensors.split(","):
        if args.gather_only:
            if (args.out / name / "differences.csv").is_file():
                rows += summarise(args.out, name)
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
        out = args.out / name
        cmd = ["flic", "evaluate", str(folder / "semantickitti"), "--setting", "both"]
        cmd += ["--frames", f"0:{args.frames}", "--out", str(out), "--jobs", str(args.jobs)]
        cmd += ["--config", str(config), "--methods", "flic0,flic14,flic14deg"]
        print("$", " ".join(cmd), flush=True)
        subprocess.run(cmd, check=True)
        script = Path(__file__).with_name("paired_differences.py")
        subprocess.run([sys.executable, str(script), str(out)], check=True)
        rows += summarise(args.out, name)
        print(pd.DataFrame(rows[-6:]).to_string(index=False), flush=True)
    write_table(args.out / "summary.csv", pd.DataFrame(rows))
    print(f"wrote {args.out}/summary.csv")


if __name__ == "__main__":
    main()
