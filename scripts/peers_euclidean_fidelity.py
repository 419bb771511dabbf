"""flic's ``euclidean`` against PCL's EuclideanClusterExtraction (scripts/peers_ref/
euclidean_driver.cpp, built by scripts/peers_fidelity.sh), 0.5 m, minimum size 1, on the
points without the ground classes (by label) of every frame of a SemanticKITTI root, and
optionally of the first frames of a second one (the synthetic sample, whose dense objects give
~30 million pairs per frame).

Per frame: whether flic's partition equals PCL's, and whether it equals the radius graph listed
pair by pair (``cKDTree.query_pairs`` + ``connected_components``, flic's implementation before
the grid method, pairs at most the tolerance apart). Timings: one thread, PCL and flic
interleaved, each side the fastest of 3 calls (the C++ times its own tree and ``extract()``).
Usage::

    python scripts/peers_euclidean_fidelity.py ../shared/data/semantickitti \
        results/peers/fidelity [S0/semantickitti [FRAMES]]
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
from scipy.sparse import coo_matrix  # noqa: E402
from scipy.sparse.csgraph import connected_components  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

from flic_cli.classes import ground_mask  # noqa: E402
from flic_cli.io import open_dataset  # noqa: E402
from flic_cli.methods.euclidean import radius_components  # noqa: E402

DRIVER = Path(os.environ.get("FLIC_REF", "/work/ref")) / "build_euclidean" / "euclidean_driver"
TOLERANCE_M = 0.5
REPEATS = 3


def same_partition(a: np.ndarray, b: np.ndarray) -> bool:
    pairs = np.unique(np.stack([a, b]), axis=1)
    return pairs.shape[1] == np.unique(a).size == np.unique(b).size


def pair_list(pts: np.ndarray) -> tuple[np.ndarray, int]:
    """The radius graph listed pair by pair (the pre-grid implementation); its pair count."""
    pairs = cKDTree(pts).query_pairs(TOLERANCE_M, output_type="ndarray")
    n = pts.shape[0]
    g = coo_matrix((np.ones(len(pairs), np.int8), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    return connected_components(g, directed=False)[1], len(pairs)


def run(dataset: str, data: Path, frames: tuple[int, int] | None, tmp: Path) -> list[dict]:
    rows = []
    for ref in open_dataset(data, frames=frames).refs():
        scan = np.fromfile(ref.path, dtype=np.float32).reshape(-1, 4)
        labels = np.fromfile(ref.label_path, dtype=np.uint32)
        pts = np.ascontiguousarray(scan[~ground_mask(labels), :3])
        pts.tofile(tmp / "in.xyz")
        cmd = [str(DRIVER), str(tmp / "in.xyz"), str(tmp / "out.labels"), str(TOLERANCE_M)]
        ref_s, flic_s = [], []
        for _ in range(REPEATS):
            res = subprocess.run(cmd, capture_output=True, text=True, check=True)
            ref_s.append(float(res.stdout.strip()))
            t = time.perf_counter()
            mine = radius_components(pts, TOLERANCE_M)
            flic_s.append(time.perf_counter() - t)
        pcl = np.fromfile(tmp / "out.labels", dtype=np.int32)
        old, n_pairs = pair_list(pts.astype(np.float64))
        rows.append({"dataset": dataset, "sequence": ref.sequence, "frame": ref.frame,
                     "points": int(pts.shape[0]), "pairs": n_pairs,
                     "identical": same_partition(pcl, mine),
                     "same_as_pair_list": same_partition(old, mine),
                     "clusters": int(np.unique(pcl).size),
                     "pcl_ms": 1000 * min(ref_s), "flic_ms": 1000 * min(flic_s)})  # fmt: skip
        print(rows[-1], flush=True)
    return rows


def main(data: Path, out: Path, sample: Path | None, sample_frames: int) -> None:
    radius_components(np.random.default_rng(0).uniform(size=(100, 3)), TOLERANCE_M)  # compile
    tmp = Path(tempfile.mkdtemp())
    rows = run("kitti", data, None, tmp)
    if sample is not None:
        rows += run("sample", sample, (0, sample_frames), tmp)
    df = pd.DataFrame(rows)
    out.mkdir(parents=True, exist_ok=True)
    df.to_csv(out / "euclidean_per_frame.csv", index=False)
    for name, d in df.groupby("dataset", sort=False):
        ratio = d["pcl_ms"] / d["flic_ms"]
        print(f"{name}: {len(d)} frames, identical to PCL {int(d['identical'].sum())}, to the "
              f"pair list {int(d['same_as_pair_list'].sum())}; median ms PCL "
              f"{d['pcl_ms'].median():.1f}, flic {d['flic_ms'].median():.1f}; PCL / flic median "
              f"{ratio.median():.2f} (min {ratio.min():.2f}); flic faster on "
              f"{int((ratio > 1).sum())} of {len(d)}")  # fmt: skip


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3]) if len(sys.argv) > 3 else None,
         int(sys.argv[4]) if len(sys.argv) > 4 else 3)  # fmt: skip
