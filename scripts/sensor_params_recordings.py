"""What every run derives from each shared recording's sensor (issue 21: methods on other
sensors): the beam table the runs read (:func:`flic_cli.sensor_params.beams_of_dataset`), the
Bridge parameters :func:`flic_cli.sensor_params.for_dataset` gives every Bridge variant, and the
column remover's run limits above 0.3 (:func:`flic_cli.sensor_params.column_run_jumps`).

Usage (from the repository root, with ``../shared`` beside it)::

    python scripts/sensor_params_recordings.py \\
        --out results/sensors-synthetic/derived-recordings/recordings.csv
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.sensor_params import (
    RUN_JUMP_FLOOR,
    beams_of_dataset,
    column_run_jumps,
    for_beams,
    street_beam_gap_deg,
)

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shared", type=Path, default=Path("../shared/data"))
    ap.add_argument(
        "--out",
        type=Path,
        default=Path("results/sensors-synthetic/derived-recordings/recordings.csv"),
    )
    args = ap.parse_args()
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


if __name__ == "__main__":
    main()
