"""Where flic's CVC and SLR differ from the public references (scripts/peers_fidelity.py runs
them): for a few frames, how many of one side's clusters span several of the other's.

Usage: python scripts/peers_ref_diff.py ../shared/data/semantickitti
(prints; the figures are quoted in docs/peers.md)
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from flic_cli.classes import ground_mask
from flic_cli.config import load_config
from flic_cli.methods.cvc import Cvc
from flic_cli.methods.slr import slr_pixels

REF = Path("/work/ref")
FRAMES = (("00", 0), ("01", 5), ("03", 3), ("04", 0), ("08", 9))


def spans(a: np.ndarray, b: np.ndarray) -> tuple[int, int, int, int]:
    """(clusters of a spanning several of b, clusters of a, of b spanning several of a, of b)."""
    pairs = np.unique(np.stack([a, b]), axis=1)
    per_a = np.bincount(np.unique(pairs[0], return_inverse=True)[1].reshape(-1))
    per_b = np.bincount(np.unique(pairs[1], return_inverse=True)[1].reshape(-1))
    return int((per_a > 1).sum()), per_a.size, int((per_b > 1).sum()), per_b.size


def main(data: Path) -> None:
    sys.path.insert(0, str(REF / "build_slr"))
    import ScanLineRun_Cluster as RefSlr

    tmp = Path(tempfile.mkdtemp())
    projection = load_config(None).projection
    for seq, fr in FRAMES:
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


if __name__ == "__main__":
    main(Path(sys.argv[1]))
