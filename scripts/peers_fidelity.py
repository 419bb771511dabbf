"""Fidelity and speed of flic's ALPINE, CVC and SLR against their public references, run
outside flic (issue 23). The references are fetched and built under /work/ref/ (see
scripts/peers_fidelity.sh); nothing of theirs is in flic.

- ALPINE against valeoai/Alpine (pure Python, imported from its clone): every scan point of the
  frame, oracle semantics (the ground truth's classes through the reference's own ``mapper``),
  split on and off; identical partitions of the thing points are counted, else the adjusted Rand
  index (ARI) is given.
- CVC against xmba15/curved_voxel_clustering (C++, PCL; scripts/peers_ref/cvc_driver.cpp): the
  frame's points without the ground classes (by label); ARI over all of them.
- SLR against the ICCVW 2021 survey's ScanLineRun_Cluster (C++/pybind11, PCL): flic's 64 x 2048
  range image of the same points, both given the same pixel points and mask; ARI over the pixels.

Timings: one thread (environment set before numpy loads), the same process and frames, each
method's call alone (file reading and projection excluded), the fastest of 3 calls per frame;
the C++ CVC times its own ``run`` (fastest of 3 processes). flic's SLR time includes computing
the pixels' points from the image; the survey's is given them.
Machine shared with other work: noisy; compare the ratios.

Usage: python scripts/peers_fidelity.py ../shared/data/semantickitti results/peers/fidelity
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from sklearn.metrics import adjusted_rand_score  # noqa: E402

from flic_cli.classes import ground_mask, learning_class  # noqa: E402
from flic_cli.config import load_config  # noqa: E402
from flic_cli.io import open_dataset  # noqa: E402
from flic_cli.labels import semantic  # noqa: E402
from flic_cli.methods.alpine import Alpine  # noqa: E402
from flic_cli.methods.cvc import Cvc  # noqa: E402
from flic_cli.methods.slr import slr_pixels  # noqa: E402

REF = Path(os.environ.get("FLIC_REF", "/work/ref"))
ALPINE_REF = REF / "valeoai+Alpine"
CVC_DRIVER = REF / "build_cvc" / "cvc_driver"
SLR_BUILD = REF / "build_slr"


def same_partition(a: np.ndarray, b: np.ndarray) -> bool:
    pairs = np.unique(np.stack([a, b]), axis=1)
    return pairs.shape[1] == np.unique(a).size == np.unique(b).size


#: Each call is timed this many times on a frame; the fastest counts (the machine is shared).
REPEATS = 3


def timed(fn, *args):  # noqa: ANN001, ANN002, ANN201
    best = float("inf")
    for _ in range(REPEATS):
        t = time.perf_counter()
        out = fn(*args)
        best = min(best, time.perf_counter() - t)
    return out, best


def main(data: Path, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    sys.path.insert(0, str(ALPINE_REF))
    from alpine import Alpine as RefAlpine  # the reference, from its clone
    from alpine_semantickitti import BBOX_WEB, THING_CLASSES, mapper

    sys.path.insert(0, str(SLR_BUILD))
    import ScanLineRun_Cluster as RefSlr  # the survey's module, built from its clone

    ref_slr = RefSlr.ScanLineRun_Cluster(0.5, 1.0)
    config = load_config(None)
    ds = open_dataset(data)
    rows = []
    tmp = Path(tempfile.mkdtemp())
    for ref in ds.refs()[: int(os.environ.get("FLIC_FRAMES", "1000"))]:
        scan = np.fromfile(ref.path, dtype=np.float32).reshape(-1, 4)
        labels = np.fromfile(ref.label_path, dtype=np.uint32)
        row = {"sequence": ref.sequence, "frame": ref.frame}
        # ---- ALPINE, oracle semantics, every point of the scan
        sem_ref = np.vectorize(mapper.__getitem__)(semantic(labels)).astype(np.int32)
        sem_flic = learning_class(labels)
        assert (sem_ref == sem_flic).all()
        things = (sem_flic >= 1) & (sem_flic <= 8)
        for split in (True, False):
            r = RefAlpine(list(THING_CLASSES), {k: list(v) for k, v in BBOX_WEB.items()},
                          k=32, split=split)  # fmt: skip
            lab_ref, t_ref = timed(r.fit_predict, scan[:, :2], sem_ref)
            mine = Alpine(split=split, min_size=1)
            lab_flic, t_flic = timed(mine.raw, scan[:, :3], sem_flic)
            tag = "alpine_split" if split else "alpine_nosplit"
            row[f"{tag}_identical"] = same_partition(lab_ref[things], lab_flic[things])
            row[f"{tag}_ari"] = adjusted_rand_score(lab_ref[things], lab_flic[things])
            row[f"{tag}_ref_ms"], row[f"{tag}_flic_ms"] = 1000 * t_ref, 1000 * t_flic
            row[f"{tag}_k_used_by_ref"] = r.k
        # ---- CVC, the points without the ground classes
        pts = scan[~ground_mask(labels), :3]
        xyz_file, lab_file = tmp / "in.xyz", tmp / "out.labels"
        np.ascontiguousarray(pts, dtype=np.float32).tofile(xyz_file)
        ref_times = []
        for _ in range(REPEATS):
            res = subprocess.run([str(CVC_DRIVER), str(xyz_file), str(lab_file)],
                                 capture_output=True, text=True, check=True)  # fmt: skip
            ref_times.append(float(res.stdout.strip()))
        cvc_ref = np.fromfile(lab_file, dtype=np.int32)
        cvc_flic, t_cvc = timed(Cvc(delta_range_m=0.5).raw, pts)  # the reference's step
        row["cvc_points"] = int(pts.shape[0])
        row["cvc_identical"] = same_partition(cvc_ref, cvc_flic)
        row["cvc_ari"] = adjusted_rand_score(cvc_ref, cvc_flic)
        row["cvc_ref_clusters"] = int(np.unique(cvc_ref).size)
        row["cvc_flic_clusters"] = int(np.unique(cvc_flic).size)
        row["cvc_ref_ms"], row["cvc_flic_ms"] = 1000 * min(ref_times), 1000 * t_cvc
        # ---- SLR on flic's range image of the same points
        keep = ~ground_mask(labels)
        image = config.projection(scan[:, :3], keep)
        h, w = image.ranges.shape
        xyz = image.to_points().astype(np.float64).reshape(h, w, 3)
        valid = image.ranges > 0
        args = (np.ascontiguousarray(xyz[..., 0]), np.ascontiguousarray(xyz[..., 1]),
                np.ascontiguousarray(xyz[..., 2]), np.ascontiguousarray(valid), h, w)  # fmt: skip
        slr_ref, t_sref = timed(ref_slr.ScanLineRun_cluster, *args)
        slr_ref = np.asarray(slr_ref)[:h, :w]
        slr_pixels(image, valid, 0.5, 1.0)  # compiled before timing
        slr_flic, t_sflic = timed(slr_pixels, image, valid, 0.5, 1.0)
        slr_flic = slr_flic.reshape(h, w)
        row["slr_pixels"] = int(valid.sum())
        row["slr_identical"] = same_partition(slr_ref[valid], slr_flic[valid])
        row["slr_ari"] = adjusted_rand_score(slr_ref[valid], slr_flic[valid])
        row["slr_ref_clusters"] = int(np.unique(slr_ref[valid]).size)
        row["slr_flic_clusters"] = int(np.unique(slr_flic[valid]).size)
        row["slr_ref_ms"], row["slr_flic_ms"] = 1000 * t_sref, 1000 * t_sflic
        rows.append(row)
        print({k: (round(v, 4) if isinstance(v, float) else v) for k, v in row.items()}, flush=True)
    df = pd.DataFrame(rows)
    df.to_csv(out / "per_frame.csv", index=False)
    summary = []
    for tag in ("alpine_split", "alpine_nosplit", "cvc", "slr"):
        summary.append(
            {
                "method": tag,
                "frames": len(df),
                "identical_frames": int(df[f"{tag}_identical"].sum()),
                "ari_min": round(float(df[f"{tag}_ari"].min()), 6),
                "ari_median": round(float(df[f"{tag}_ari"].median()), 6),
                "ref_ms_median": round(float(df[f"{tag}_ref_ms"].median()), 3),
                "flic_ms_median": round(float(df[f"{tag}_flic_ms"].median()), 3),
                "speedup_median": round(
                    float((df[f"{tag}_ref_ms"] / df[f"{tag}_flic_ms"]).median()), 2
                ),
            }
        )
    pd.DataFrame(summary).to_csv(out / "summary.csv", index=False)
    print(pd.DataFrame(summary).to_string(index=False))


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
