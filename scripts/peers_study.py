"""The field's clusterers against their public reference code, run outside flic (issue 23).

The references are fetched and built under ``$FLIC_REF`` (default /work/ref) by
``scripts/peers_fidelity.sh``; nothing of theirs is in flic. From the repository root, with the
dev install (step ``peers-fidelity`` of ``scripts/make_results.sh`` runs all four)::

    python scripts/peers_study.py clusterers ../shared/data/semantickitti results/peers/fidelity
    python scripts/peers_study.py ref-diff ../shared/data/semantickitti > results/peers/fidelity/ref_diff.txt
    python scripts/peers_study.py euclidean ../shared/data/semantickitti results/peers/fidelity \
        S0/semantickitti 3
    python scripts/peers_study.py ablation ../shared/data/semantickitti results/peers/fidelity --every 5

``python scripts/peers_study.py STUDY --help`` says what each one measures and writes. Every
timing runs on one thread (the environment is set before numpy loads).
"""

# ruff: noqa: E501  (the ablation's edits are lines of C++ source)
from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import sysconfig  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from _studies import Studies, run_studies  # noqa: E402  # scripts/_studies.py
from scipy.sparse import coo_matrix  # noqa: E402
from scipy.sparse.csgraph import connected_components  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402
from sklearn.metrics import adjusted_rand_score  # noqa: E402

from flic_cli.classes import ground_mask, learning_class  # noqa: E402
from flic_cli.config import load_config  # noqa: E402
from flic_cli.io import open_dataset  # noqa: E402
from flic_cli.labels import semantic  # noqa: E402
from flic_cli.methods.alpine import Alpine  # noqa: E402
from flic_cli.methods.cvc import Cvc  # noqa: E402
from flic_cli.methods.euclidean import radius_components  # noqa: E402
from flic_cli.methods.slr import slr_pixels  # noqa: E402

# ---- shared ----------------------------------------------------------------------------------

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


# ---- clusterers: ALPINE, CVC, SLR ------------------------------------------------------------------


def _clusterers(data: Path, out: Path) -> None:
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


def clusterers(args: argparse.Namespace) -> None:
    """Fidelity and speed of flic's ALPINE, CVC and SLR against their public references.

    The references run outside flic, fetched and built under $FLIC_REF (see
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
    """
    _clusterers(args.data, args.out)


def _clusterers_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", type=Path, help="a SemanticKITTI root (the 50 shared frames)")
    p.add_argument("out", type=Path, help="writes per_frame.csv and summary.csv there")


# ---- ref-diff --------------------------------------------------------------------------------------

DIFF_FRAMES = (("00", 0), ("01", 5), ("03", 3), ("04", 0), ("08", 9))


def spans(a: np.ndarray, b: np.ndarray) -> tuple[int, int, int, int]:
    """(clusters of a spanning several of b, clusters of a, of b spanning several of a, of b)."""
    pairs = np.unique(np.stack([a, b]), axis=1)
    per_a = np.bincount(np.unique(pairs[0], return_inverse=True)[1].reshape(-1))
    per_b = np.bincount(np.unique(pairs[1], return_inverse=True)[1].reshape(-1))
    return int((per_a > 1).sum()), per_a.size, int((per_b > 1).sum()), per_b.size


def _ref_diff(data: Path) -> None:
    sys.path.insert(0, str(REF / "build_slr"))
    import ScanLineRun_Cluster as RefSlr

    tmp = Path(tempfile.mkdtemp())
    projection = load_config(None).projection
    for seq, fr in DIFF_FRAMES:
        base = data / "sequences" / seq
        scan = np.fromfile(base / "velodyne" / f"{fr:06d}.bin", dtype=np.float32).reshape(-1, 4)
        labels = np.fromfile(base / "labels" / f"{fr:06d}.label", dtype=np.uint32)
        keep = ~ground_mask(labels)
        pts = np.ascontiguousarray(scan[keep, :3])
        pts.tofile(tmp / "in.xyz")
        subprocess.run([str(REF / "build_cvc" / "cvc_driver"), str(tmp / "in.xyz"),
                        str(tmp / "out.labels")], check=True, capture_output=True)  # fmt: skip
        ref = np.fromfile(tmp / "out.labels", dtype=np.int32)
        mine = Cvc(delta_range_m=0.5).raw(pts)  # the reference's defaults
        zero = ref == 0  # the reference's first cluster, where its unclustered points also go
        a = spans(ref[~zero], mine[~zero])
        print(f"{seq}/{fr:06d} CVC: reference cluster 0 holds {int(zero.sum())} points over "
              f"{np.unique(mine[zero]).size} flic clusters; elsewhere {a[0]} of {a[1]} reference "
              f"clusters span several flic clusters, {a[2]} of {a[3]} flic clusters span several "
              "reference clusters")  # fmt: skip
        image = projection(scan[:, :3], keep)
        h, w = image.ranges.shape
        xyz = image.to_points().astype(np.float64).reshape(h, w, 3)
        valid = image.ranges > 0
        ref_slr = np.asarray(RefSlr.ScanLineRun_Cluster(0.5, 1.0).ScanLineRun_cluster(
            np.ascontiguousarray(xyz[..., 0]), np.ascontiguousarray(xyz[..., 1]),
            np.ascontiguousarray(xyz[..., 2]), np.ascontiguousarray(valid), h, w,
        ))[:h, :w][valid]  # fmt: skip
        mine_slr = slr_pixels(image, valid, 0.5, 1.0).reshape(h, w)[valid]
        b = spans(ref_slr, mine_slr)
        print(
            f"{seq}/{fr:06d} SLR: {b[0]} of {b[1]} reference clusters span several flic "
            f"clusters, {b[2]} of {b[3]} flic clusters span several reference clusters"
        )


def ref_diff(args: argparse.Namespace) -> None:
    """Where flic's CVC and SLR differ from the public references, on five frames.

    For each frame (the references as ``clusterers`` runs them), how many of one side's clusters
    span several of the other's.
    """
    _ref_diff(args.data)


def _ref_diff_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", type=Path, help="a SemanticKITTI root (prints)")


# ---- euclidean -------------------------------------------------------------------------------------

EUCLIDEAN_DRIVER = REF / "build_euclidean" / "euclidean_driver"
TOLERANCE_M = 0.5


def pair_list(pts: np.ndarray) -> tuple[np.ndarray, int]:
    """The radius graph listed pair by pair (the pre-grid implementation); its pair count."""
    pairs = cKDTree(pts).query_pairs(TOLERANCE_M, output_type="ndarray")
    n = pts.shape[0]
    g = coo_matrix((np.ones(len(pairs), np.int8), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    return connected_components(g, directed=False)[1], len(pairs)


def euclidean_rows(
    dataset: str, data: Path, frames: tuple[int, int] | None, tmp: Path
) -> list[dict]:
    rows = []
    for ref in open_dataset(data, frames=frames).refs():
        scan = np.fromfile(ref.path, dtype=np.float32).reshape(-1, 4)
        labels = np.fromfile(ref.label_path, dtype=np.uint32)
        pts = np.ascontiguousarray(scan[~ground_mask(labels), :3])
        pts.tofile(tmp / "in.xyz")
        cmd = [
            str(EUCLIDEAN_DRIVER),
            str(tmp / "in.xyz"),
            str(tmp / "out.labels"),
            str(TOLERANCE_M),
        ]
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


def _euclidean(data: Path, out: Path, sample: Path | None, sample_frames: int) -> None:
    radius_components(np.random.default_rng(0).uniform(size=(100, 3)), TOLERANCE_M)  # compile
    tmp = Path(tempfile.mkdtemp())
    rows = euclidean_rows("kitti", data, None, tmp)
    if sample is not None:
        rows += euclidean_rows("sample", sample, (0, sample_frames), tmp)
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


def euclidean(args: argparse.Namespace) -> None:
    """flic's ``euclidean`` against PCL's EuclideanClusterExtraction, frame by frame.

    PCL through scripts/peers_ref/euclidean_driver.cpp (built by scripts/peers_fidelity.sh),
    0.5 m, minimum size 1, on the points without the ground classes (by label) of every frame of a SemanticKITTI root, and
    optionally of the first frames of a second one (the synthetic sample, whose dense objects give
    ~30 million pairs per frame).

    Per frame: whether flic's partition equals PCL's, and whether it equals the radius graph listed
    pair by pair (``cKDTree.query_pairs`` + ``connected_components``, flic's implementation before
    the grid method, pairs at most the tolerance apart). Timings: one thread, PCL and flic
    interleaved, each side the fastest of 3 calls (the C++ times its own tree and ``extract()``).
    """
    _euclidean(args.data, args.out, args.sample, args.sample_frames)


def _euclidean_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", type=Path, help="a SemanticKITTI root (every frame)")
    p.add_argument("out", type=Path, help="writes euclidean_per_frame.csv there")
    p.add_argument("sample", type=Path, nargs="?", default=None, help="a second root")
    p.add_argument("sample_frames", type=int, nargs="?", default=3, help="its first frames")


# ---- ablation --------------------------------------------------------------------------------------

CVC_SRC = REF / "xmba15+curved_voxel_clustering"
SLR_SRC = (
    REF / "placeforyiming+ICCVW21-LiDAR-Panoptic-Segmentation-TradiCV-Survey-of-Point-Cloud-Cluster"
    / "PC_cluster" / "ScanLineRun_cluster" / "ScanLineRun_Cluster.cpp"
)  # fmt: skip
HERE = Path(__file__).resolve().parent
BUILD = REF / "build_ablation"
PCL = ["-I/usr/include/pcl-1.13", "-I/usr/include/eigen3"]

CVC_STEPS = ("published", "flush", "explore", "min1", "azimuth", "double")
SLR_STEPS = ("published", "unionfind", "nearest", "nomakeup", "emptyline")

# (original text in the clone, replacement): each replacement keeps the original under
# ``#if !FIX_...`` so that every switch off gives the published code.
CVC_EDITS = (
    (  # flush: the -1 group is dropped instead of being carried into the first cluster
        "            if (curClusterIdx >= 0) {\n                allClusters.emplace_back(std::move(curCluster));\n            }\n",
        "            if (curClusterIdx >= 0) {\n                allClusters.emplace_back(std::move(curCluster));\n            }\n#if FIX_FLUSH\n            else {\n                curCluster.clear();\n            }\n#endif\n",
    ),
    (  # explore: no skipping of labelled points
        "        if (clusterIndices[i] >= 0) {\n            continue;\n        }\n",
        "#if !FIX_EXPLORE\n        if (clusterIndices[i] >= 0) {\n            continue;\n        }\n#endif\n",
    ),
    (  # double: the range in double precision
        "        gridPoint[0] = point.getVector3fMap().norm();\n",
        "#if FIX_DOUBLE\n        gridPoint[0] = std::sqrt(double(point.x) * point.x + double(point.y) * point.y + double(point.z) * point.z);\n#else\n        gridPoint[0] = point.getVector3fMap().norm();\n#endif\n",
    ),
    (  # azimuth: atan2 for every point
        "        gridPoint[2] = almostEquals<double>(point.x, 0) ? 0 : std::atan2(point.y, point.x);\n",
        "#if FIX_AZIMUTH\n        gridPoint[2] = std::atan2(double(point.y), double(point.x));\n#else\n        gridPoint[2] = almostEquals<double>(point.x, 0) ? 0 : std::atan2(point.y, point.x);\n#endif\n",
    ),
    (  # azimuth: bins from -pi, exactly ceil(2 pi / res) of them
        "    return gridParam;\n}\n",
        "#if FIX_AZIMUTH\n    gridParam.minPoint[2] = -M_PI;\n    gridParam.bucketNums[2] = std::ceil(2 * M_PI / m_gridResolutions[2]);\n#endif\n    return gridParam;\n}\n",
    ),
    (  # azimuth: floor and wrap of the azimuth index
        "        gridIndices[i] = (gridPoint[i] - gridParam.minPoint[i]) / m_gridResolutions[i];\n",
        "        gridIndices[i] = (gridPoint[i] - gridParam.minPoint[i]) / m_gridResolutions[i];\n#if FIX_AZIMUTH\n        if (i == 2) {\n            gridIndices[i] = static_cast<int>(std::floor((gridPoint[i] + M_PI) / m_gridResolutions[i])) % gridParam.bucketNums[2];\n        }\n#endif\n",
    ),
)

SLR_EDITS = (
    (  # the switches, read from the environment at each call (one build for every variant)
        "#include <pcl/point_types.h>\n",
        "#include <cstdlib>\n#include <pcl/point_types.h>\nstatic bool fix_(const char* name) { const char* v = std::getenv(name); return v && v[0] == '1'; }\n",
    ),
    (  # a union-find over labels, next to the label lists
        "        std::vector<std::vector<int>> label_idx_ ;",
        '        std::vector<std::vector<int>> label_idx_ ;\n        const bool FIX_UNIONFIND = fix_("FIX_UNIONFIND"), FIX_NEAREST = fix_("FIX_NEAREST"), FIX_NOMAKEUP = fix_("FIX_NOMAKEUP"), FIX_EMPTYLINE = fix_("FIX_EMPTYLINE");\n        std::vector<int> parent_;\n        auto find_ = [&](int l) { if (!FIX_UNIONFIND) return l; while (parent_[l] != l) l = parent_[l] = parent_[parent_[l]]; return l; };',
    ),
    (  # new labels of the first line are their own roots
        "                    label_idx_.push_back(runs_idx_[i][j]);\n\n",
        "                    label_idx_.push_back(runs_idx_[i][j]);\n                    parent_.push_back(label_idx_.size() - 1);\n\n",
    ),
    (  # new labels later are their own roots
        "                    label_idx_.push_back(runs_idx_[i][j]);\n                    runlabel = label_idx_.size() - 1;",
        "                    label_idx_.push_back(runs_idx_[i][j]);\n                    parent_.push_back(label_idx_.size() - 1);\n                    runlabel = label_idx_.size() - 1;",
    ),
    (  # merged labels point at the label they went into
        "                            label_idx_[labelsToMerge[label]].clear(); // will cause some null label, but its okay",
        "                            label_idx_[labelsToMerge[label]].clear(); // will cause some null label, but its okay\n                            parent_[labelsToMerge[label]] = labelsToMerge[0];",
    ),
    (  # nearest: the nearest point of the line above instead of the proportional index
        "                    int neighbor_idx = floor( (float) (point_idx_start+k) / runsCurrent_.size() * runsAbove_.size() );\n",
        "                    int neighbor_idx = floor( (float) (point_idx_start+k) / runsCurrent_.size() * runsAbove_.size() );\n                    if (FIX_NEAREST) {\n                    if (runsAbove_.empty()) continue;\n                    float best = 1e30f; const auto& c = runsCurrent_[point_idx_start+k]; for (std::size_t q = 0; q < runsAbove_.size(); ++q) { const auto& a = runsAbove_[q]; float d = (c.x-a.x)*(c.x-a.x)+(c.y-a.y)*(c.y-a.y)+(c.z-a.z)*(c.z-a.z); if (d < best) { best = d; neighbor_idx = q; } }\n                    }\n",
    ),
    (  # labels read from the line above go through the union-find
        "                        int label = neighborPoint.label;\n",
        "                        int label = find_(neighborPoint.label);\n",
    ),
    (  # nomakeup: skip the brute-force search of lines 1-4 above
        "                if (labelsToMerge.empty())\n                {\n                    // ************** make-up search ************** //",
        "                if (labelsToMerge.empty())\n                {\n                    if (!FIX_NOMAKEUP) {\n                    // ************** make-up search ************** //",
    ),
    (
        "                    if (!labelsToMerge.empty())\n                    {\n                        goto GotLabel;\n                    }\n",
        "                    if (!labelsToMerge.empty())\n                    {\n                        goto GotLabel;\n                    }\n                    }\n",
    ),
    (  # emptyline: an empty row is a line above with no points
        "            if(frame_idx_[i].size() == 0 ){\n                continue;\n            }\n",
        "            if(frame_idx_[i].size() == 0 ){\n                if (FIX_EMPTYLINE && !label_idx_.empty()) { runsAboveAboveAboveAbove_ = runsAboveAboveAbove_; runsAboveAboveAbove_ = runsAboveAbove_; runsAboveAbove_ = runsAbove_; runsAbove_.clear(); }\n                continue;\n            }\n",
    ),
)


def patched(text: str, edits: tuple[tuple[str, str], ...], name: str) -> str:
    for old, new in edits:
        if text.count(old) != 1:
            raise SystemExit(f"{name}: the clone's source is not the one these edits were made for")
        text = text.replace(old, new)
    return text


def flags(steps: tuple[str, ...], upto: int) -> list[str]:
    return [f"-DFIX_{s.upper()}={int(0 < k <= upto)}" for k, s in enumerate(steps) if k]


def build() -> None:
    BUILD.mkdir(parents=True, exist_ok=True)
    cvc = BUILD / "CurvedVoxelClustering.cpp"
    cvc.write_text(
        patched((CVC_SRC / "src" / "CurvedVoxelClustering.cpp").read_text(), CVC_EDITS, "CVC")
    )
    slr = BUILD / "ScanLineRun_Cluster.cpp"
    slr.write_text(patched(SLR_SRC.read_text(), SLR_EDITS, "SLR"))
    for k in range(len(CVC_STEPS)):
        out = BUILD / f"cvc_{k}"
        if not out.exists():
            subprocess.run(["g++", "-O3", "-std=c++17", *flags(CVC_STEPS, k),
                            f"-I{CVC_SRC / 'include'}", *PCL, str(cvc),
                            str(HERE / "peers_ref" / "cvc_driver.cpp"), "-o", str(out),
                            "-lpcl_common"], check=True)  # fmt: skip
    pyinc = sysconfig.get_paths()["include"]
    ext = sysconfig.get_config_var("EXT_SUFFIX")
    out = BUILD / f"ScanLineRun_Cluster{ext}"
    if not out.exists():
        subprocess.run(["g++", "-O3", "-std=c++14", "-shared", "-fPIC", *PCL, f"-I{pyinc}",
                        str(slr), "-o", str(out), "-lpcl_common"], check=True)  # fmt: skip


def load_slr():  # noqa: ANN201
    ext = sysconfig.get_config_var("EXT_SUFFIX")
    spec = importlib.util.spec_from_file_location(
        "ScanLineRun_Cluster", BUILD / f"ScanLineRun_Cluster{ext}"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.ScanLineRun_Cluster(0.5, 1.0)


def slr_switches(upto: int) -> None:
    """Set the environment switches the SLR build reads (steps 1..upto on)."""
    for k, step in enumerate(SLR_STEPS):
        if k:
            os.environ[f"FIX_{step.upper()}"] = "1" if k <= upto else "0"


def singletons(labels: np.ndarray) -> np.ndarray:
    """Points in no cluster (< 0) as one cluster each."""
    out = labels.astype(np.int64).copy()
    none = out < 0
    out[none] = out.max(initial=0) + 1 + np.arange(int(none.sum()))
    return out


def _ablation(args: argparse.Namespace) -> None:
    build()
    projection = load_config(None).projection
    slr_ref = load_slr()
    tmp = Path(tempfile.mkdtemp())
    rows = []
    refs = open_dataset(args.data).refs()
    for ref in refs[: args.frames or None : args.every]:
        scan = np.fromfile(ref.path, dtype=np.float32).reshape(-1, 4)
        labels = np.fromfile(ref.label_path, dtype=np.uint32)
        keep = ~ground_mask(labels)
        pts = np.ascontiguousarray(scan[keep, :3])
        pts.tofile(tmp / "in.xyz")
        mine = Cvc(delta_range_m=0.5).raw(pts)
        for k, step in enumerate(CVC_STEPS):
            cmd = [str(BUILD / f"cvc_{k}"), str(tmp / "in.xyz"), str(tmp / "out.labels")]
            if k >= CVC_STEPS.index("min1"):
                cmd.append("1")
            subprocess.run(cmd, check=True, capture_output=True)
            theirs = singletons(np.fromfile(tmp / "out.labels", dtype=np.int32))
            rows.append({"method": "cvc", "step": k, "variant": step, "sequence": ref.sequence,
                         "frame": ref.frame, "ari": adjusted_rand_score(theirs, mine),
                         "identical": same_partition(theirs, mine),
                         "ref_clusters": int(np.unique(theirs).size),
                         "flic_clusters": int(np.unique(mine).size)})  # fmt: skip
        image = projection(scan[:, :3], keep)
        h, w = image.ranges.shape
        xyz = image.to_points().astype(np.float64).reshape(h, w, 3)
        valid = image.ranges > 0
        call = (np.ascontiguousarray(xyz[..., 0]), np.ascontiguousarray(xyz[..., 1]),
                np.ascontiguousarray(xyz[..., 2]), np.ascontiguousarray(valid), h, w)  # fmt: skip
        mine = slr_pixels(image, valid, 0.5, 1.0).reshape(h, w)[valid]
        for k, step in enumerate(SLR_STEPS):
            slr_switches(k)
            theirs = np.asarray(slr_ref.ScanLineRun_cluster(*call))[:h, :w][valid]
            rows.append({"method": "slr", "step": k, "variant": step, "sequence": ref.sequence,
                         "frame": ref.frame, "ari": adjusted_rand_score(theirs, mine),
                         "identical": same_partition(theirs, mine),
                         "ref_clusters": int(np.unique(theirs).size),
                         "flic_clusters": int(np.unique(mine).size)})  # fmt: skip
        print(ref.sequence, ref.frame, [f"{r['variant']} {r['ari']:.4f}" for r in rows[-11:]],
              flush=True)  # fmt: skip
    df = pd.DataFrame(rows)
    args.out.mkdir(parents=True, exist_ok=True)
    df.to_csv(args.out / "ablation_per_frame.csv", index=False)
    summary = (
        df.groupby(["method", "step", "variant"])
        .agg(
            frames=("ari", "size"),
            identical_frames=("identical", "sum"),
            ari_min=("ari", "min"),
            ari_median=("ari", "median"),
            ref_clusters_median=("ref_clusters", "median"),
            flic_clusters_median=("flic_clusters", "median"),
        )  # fmt: skip
        .reset_index()
    )
    summary.to_csv(args.out / "ablation.csv", index=False)
    print(summary.to_string(index=False))


def ablation(args: argparse.Namespace) -> None:
    """Why flic's CVC and SLR differ from their references: their departures removed one by one.

    Builds variants of the two references OUTSIDE flic, under ``$FLIC_REF/build_ablation/`` (default
    /work/ref): their clones' source, each departure wrapped in a preprocessor switch (the switches
    are written here as textual edits of the clone; nothing of theirs enters flic), compiled once per
    set of switches (CVC) or once, the switches read from the environment at each call (SLR).
    Then, on every frame of the shared SemanticKITTI root (``--frames N``: the first N; ``--every K``:
    every K-th), the adjusted Rand index (ARI) and identity of each cumulative variant against flic at
    the reference's parameters, on the same input as ``clusterers``:

    CVC (xmba15/curved_voxel_clustering, 0.5 m / 3 deg / 1.3 deg), points without the ground classes;
    points a variant leaves in no cluster count as one cluster each:

    0. as published;
    1. ``flush``: points left in no cluster are not put into the first cluster (``getAllClusters``
       starts its sweep at the -1 entries and never closes that group);
    2. ``explore``: every point looks at its neighbourhood, also one already labelled as someone's
       neighbour (the loop ``continue``s on labelled points, so a chain through them is cut);
    3. ``min1``: ``numMinPoints`` 1 (a cluster opens only where a neighbourhood has 3 points);
    4. ``azimuth``: azimuth bins from -180 deg, ``ceil(360 / 1.3)`` of them, wrapping exactly (the
       reference starts at the scan's smallest azimuth and wraps its first bin onto its last,
       partial one; and it sets the azimuth of points with ``|x| <= 1e-8`` to 0);
    5. ``double``: the range in double precision (the reference's ``norm()`` is float).

    SLR (the ICCVW 2021 survey's ScanLineRun_Cluster, 0.5 m / 1.0 m), flic's 64 x 2048 image:

    0. as published;
    1. ``unionfind``: labels read from the line above resolved through the merges (the reference
       moves a merged label's point list but leaves the stale label on the line above's points, so a
       later run can join, or be given, an emptied label);
    2. ``nearest``: each point's nearest point of the line above (the reference takes the point at
       the same proportional index, ``floor(k / n_current * n_above)``);
    3. ``nomakeup``: no brute-force "make-up" search of the lines 1 to 4 above when a run found no
       label;
    4. ``emptyline``: the line above is the image row above, also when that row is empty (the
       reference's "above" is the last non-empty line).
    """
    _ablation(args)


def _ablation_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", type=Path)
    p.add_argument("out", type=Path)
    p.add_argument("--frames", type=int, default=0, help="only the first N frames (0: all)")
    p.add_argument("--every", type=int, default=1, help="every K-th frame of those")


# ---- the command line --------------------------------------------------------------------------

STUDIES: Studies = {
    "clusterers": (clusterers, _clusterers_arguments),
    "ref-diff": (ref_diff, _ref_diff_arguments),
    "euclidean": (euclidean, _euclidean_arguments),
    "ablation": (ablation, _ablation_arguments),
}


def main(argv: list[str] | None = None) -> None:
    run_studies(__doc__, STUDIES, argv)


if __name__ == "__main__":
    main()
