"""Why flic's CVC and SLR differ from their public references, shown by removing the references'
departures one at a time (issue 23).

Builds variants of the two references OUTSIDE flic, under ``$FLIC_REF/build_ablation/`` (default
/work/ref): their clones' source, each departure wrapped in a preprocessor switch (the switches
are written here as textual edits of the clone; nothing of theirs enters flic), compiled once per
set of switches (CVC) or once, the switches read from the environment at each call (SLR).
Then, on every frame of the shared SemanticKITTI root (``--frames N``: the first N; ``--every K``:
every K-th), the adjusted Rand index (ARI) and identity of each cumulative variant against flic at
the reference's parameters, on the same input as scripts/peers_fidelity.py:

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

Usage::

    python scripts/peers_ref_ablation.py ../shared/data/semantickitti results/peers/fidelity \
        --every 5
"""

# ruff: noqa: E501  (the edits below are lines of C++ source)
from __future__ import annotations

import os

os.environ["OMP_NUM_THREADS"] = "1"

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import subprocess  # noqa: E402
import sysconfig  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from sklearn.metrics import adjusted_rand_score  # noqa: E402

from flic_cli.classes import ground_mask  # noqa: E402
from flic_cli.config import load_config  # noqa: E402
from flic_cli.io import open_dataset  # noqa: E402
from flic_cli.methods.cvc import Cvc  # noqa: E402
from flic_cli.methods.slr import slr_pixels  # noqa: E402

REF = Path(os.environ.get("FLIC_REF", "/work/ref"))
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


def same_partition(a: np.ndarray, b: np.ndarray) -> bool:
    pairs = np.unique(np.stack([a, b]), axis=1)
    return pairs.shape[1] == np.unique(a).size == np.unique(b).size


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--frames", type=int, default=0, help="only the first N frames (0: all)")
    ap.add_argument("--every", type=int, default=1, help="every K-th frame of those")
    args = ap.parse_args()
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


if __name__ == "__main__":
    main()
