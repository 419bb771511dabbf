"""Decode an Ouster pcap with ouster-sdk and save what flic's comparison needs (runs OUTSIDE flic).

Run with the interpreter of a separate venv that has ouster-sdk (its pins clash with flic's
environment, see docs/sensors.md), e.g.::

    /work/ref/ouster-venv/bin/python scripts/sensors/ouster_sdk_dump.py REC.pcap META.json OUT.npz

Saves per complete scan ``range_<k>`` (destaggered (H, W) uint32, mm), ``xyz_<k>`` ((H, W, 3)
float64 metres, sensor frame, ouster-sdk's XYZLut, destaggered), ``frame_id_<k>``, and
``sdk_version``. Imports only ouster-sdk and numpy.
"""

from __future__ import annotations

import sys

import numpy as np
from ouster.sdk import __version__ as sdk_version  # type: ignore[attr-defined]
from ouster.sdk import core, open_source


def main(pcap: str, meta: str, out: str) -> None:
    source = open_source(pcap, meta=[meta], collate=False, sensor_idx=0)
    info = source.sensor_info[0]
    lut = core.XYZLut(info, use_extrinsics=False)
    arrays: dict[str, np.ndarray] = {"sdk_version": np.array(sdk_version)}
    k = 0
    for frame_set in source:  # ouster-sdk 1.0: FrameSet -> its LidarFrames ("scans")
        scans = [f for f in frame_set.valid_frames() if f is not None]
        if not scans or not scans[0].complete(info.format.column_window):
            continue
        scan = scans[0]
        rng = scan.field(core.ChanField.RANGE)
        arrays[f"range_{k}"] = core.destagger(info, rng)
        arrays[f"xyz_{k}"] = core.destagger(info, lut(scan))
        arrays[f"frame_id_{k}"] = np.array(scan.frame_id)
        k += 1
    np.savez(out, **arrays)
    print(f"{pcap}: {k} complete scan(s) -> {out}")


if __name__ == "__main__":
    main(*sys.argv[1:4])
