"""The shared sensor recordings the scripts of this folder run on (../shared/data/sensors)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SENSORS = ROOT.parent / "shared" / "data" / "sensors"
RECORDINGS = [
    "ouster/OS-2-128-U1_v2.3.0_1024x10.pcap",
    "ouster/OS-1-64_1024x10_fw20.pcap",
    "velodyne/vlp16_velodyne_example.pcap",
    "pcd/robosense_helios16p_1691031766781547066.pcd",
    "velodyne/nebula_vlp16/1673400472138016708.pcd",
    "nuscenes/n015-2018-07-24-11-22-45+0800__LIDAR_TOP__1532402927647951.pcd.bin",
]
