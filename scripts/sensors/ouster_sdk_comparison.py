"""flic's Ouster decoder against ouster-sdk, pixel by pixel, on the shared recordings.

flic decodes Ouster packets itself (docs/sensors.md says why); this script shows that its range
images equal ouster-sdk's. ouster-sdk runs in its own venv (outside flic; its pins clash with
flic's environment) through ``ouster_sdk_dump.py``; this script runs in flic's environment::

    python scripts/sensors/ouster_sdk_comparison.py \
        --sdk-python /work/ref/ouster-venv/bin/python \
        --out results/sensors/ouster_sdk_comparison.csv

Per recording and scan: pixels, valid pixels (range > 0) of each, pixels whose range differs
(mm, destaggered), and the largest distance between flic's and ouster-sdk's points (metres,
over the valid pixels).
"""

from __future__ import annotations

import argparse
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.io import open_dataset
from flic_cli.io.ouster import decode_frames, destagger
from flic_cli.io.pcap import read_payloads

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data" / "sensors" / "ouster"
RECORDINGS = [
    ("OS-2-128-U1_v2.3.0_1024x10.pcap", "OS-2-128-U1_v2.3.0_1024x10.json"),
    ("OS-1-64_1024x10_fw20.pcap", "OS-1-64_sensor_config_reduced.json"),
]


def compare(pcap: Path, meta: Path, sdk_python: str) -> list[dict]:
    """Rows of the comparison for one recording."""
    with tempfile.TemporaryDirectory() as tmp:
        npz = Path(tmp) / "sdk.npz"
        subprocess.run(
            [sdk_python, str(ROOT / "scripts/sensors/ouster_sdk_dump.py"), pcap, meta, npz],
            check=True,
            capture_output=True,
        )
        sdk = dict(np.load(npz))
    ds = open_dataset(pcap)
    rows = []
    for ref in ds.refs():
        info = ds.infos[ref.sequence]
        state = info.state
        (raw,) = decode_frames(read_payloads(state.index, state.packets[ref.frame]), state.meta)
        ours = destagger(raw.range_mm, state.meta.pixel_shift)
        frame = ds.load(ref)
        k = ref.frame
        theirs = sdk[f"range_{k}"].astype(np.uint32)
        xyz = sdk[f"xyz_{k}"].reshape(-1, 3)[frame.image.point_pixel]
        rows.append(
            {
                "recording": pcap.name,
                "metadata": meta.name,
                "profile": state.meta.profile,
                "beams": ours.shape[0],
                "columns": ours.shape[1],
                "frame": k,
                "frame_id": int(raw.frame_id),
                "sdk_frame_id": int(sdk[f"frame_id_{k}"]),
                "pixels": ours.size,
                "flic_valid": int(np.count_nonzero(ours)),
                "sdk_valid": int(np.count_nonzero(theirs)),
                "range_differing_pixels": int(np.count_nonzero(ours != theirs)),
                "image_ranges_equal_sdk_m": bool(
                    np.array_equal(frame.image.ranges, (theirs * 0.001).astype(np.float32))
                ),
                "xyz_max_abs_diff_m": float(np.abs(frame.points - xyz).max()),
                "ouster_sdk": str(sdk["sdk_version"]),
            }
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sdk-python", default="/work/ref/ouster-venv/bin/python")
    parser.add_argument(
        "--out", type=Path, default=ROOT / "results/sensors/ouster_sdk_comparison.csv"
    )
    args = parser.parse_args()
    rows = []
    for pcap, meta in RECORDINGS:
        rows += compare(SHARED / pcap, SHARED / meta, args.sdk_python)
    table = pd.DataFrame(rows)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(args.out, index=False)
    print(table.to_string(index=False))


if __name__ == "__main__":
    main()
