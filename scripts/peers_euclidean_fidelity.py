"""flic's ``euclidean`` against PCL's EuclideanClusterExtraction (scripts/peers_ref/
euclidean_driver.cpp, built by scripts/peers_fidelity.sh), 0.5 m, minimum size 1, on the
points without the ground classes (by label) of the first two frames of each shared sequence.

Timings: one thread, each side the fastest of 3 calls (the C++ times its own tree and extract()).
Usage:
    python scripts/peers_euclidean_fidelity.py ../shared/data/semantickitti results/peers/fidelity
"""

from __future__ import annotations

import os

os.environ["OMP_NUM_THREADS"] = "1"

import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from flic_cli.classes import ground_mask  # noqa: E402
from flic_cli.io import open_dataset  # noqa: E402
from flic_cli.methods.euclidean import radius_components  # noqa: E402

DRIVER = Path(os.environ.get("FLIC_REF", "/work/ref")) / "build_euclidean" / "euclidean_driver"
TOLERANCE_M = 0.5
REPEATS = 3


def main(data: Path, out: Path) -> None:
    tmp = Path(tempfile.mkdtemp())
    rows = []
    for ref in open_dataset(data, frames=(0, 2)).refs():
        scan = np.fromfile(ref.path, dtype=np.float32).reshape(-1, 4)
        labels = np.fromfile(ref.label_path, dtype=np.uint32)
        pts = np.ascontiguousarray(scan[~ground_mask(labels), :3])
        pts.tofile(tmp / "in.xyz")
        ref_s = []
        for _ in range(REPEATS):
            cmd = [str(DRIVER), str(tmp / "in.xyz"), str(tmp / "out.labels"), str(TOLERANCE_M)]
            res = subprocess.run(cmd, capture_output=True, text=True, check=True)
            ref_s.append(float(res.stdout.strip()))
        pcl = np.fromfile(tmp / "out.labels", dtype=np.int32)
        flic_s = []
        for _ in range(REPEATS):
            t = time.perf_counter()
            mine = radius_components(pts, TOLERANCE_M)
            flic_s.append(time.perf_counter() - t)
        pairs = np.unique(np.stack([pcl, mine]), axis=1)
        identical = pairs.shape[1] == np.unique(pcl).size == np.unique(mine).size
        rows.append({"sequence": ref.sequence, "frame": ref.frame, "points": int(pts.shape[0]),
                     "identical": bool(identical), "clusters": int(np.unique(pcl).size),
                     "pcl_ms": 1000 * min(ref_s), "flic_ms": 1000 * min(flic_s)})  # fmt: skip
        print(rows[-1], flush=True)
    df = pd.DataFrame(rows)
    df.to_csv(out / "euclidean_per_frame.csv", index=False)
    print(f"identical {int(df['identical'].sum())} of {len(df)}; median ms PCL "
          f"{df['pcl_ms'].median():.1f}, flic {df['flic_ms'].median():.1f}; median ratio "
          f"flic / PCL {(df['flic_ms'] / df['pcl_ms']).median():.2f}")  # fmt: skip


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
