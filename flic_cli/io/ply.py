"""A segmented frame as a PLY point cloud, for CloudCompare, MeshLab, Open3D and the like.

Format (written with :mod:`plyfile`): ``binary_little_endian 1.0``, one element ``vertex`` per
point with the properties, in this order:

===========  =========  ====================================================================
property     type       meaning
===========  =========  ====================================================================
x, y, z      float      coordinates in metres, sensor frame (x forward, y left, z up)
cluster      int        cluster id, 0 = none (unclustered or ground)
red, green,  uchar      display colour: clusters a fixed colour per id, ground
blue                    :data:`GROUND_RGB`, unclustered :data:`UNCLUSTERED_RGB`
===========  =========  ====================================================================

The comment lines of the header say what the colours mean. Checked readers: plyfile (every
field, in the tests), Open3D 0.20 (``open3d.io.read_point_cloud``: points and colours;
``open3d.t.io.read_point_cloud`` also keeps ``cluster`` as an attribute), pymeshlab 2025.7
(MeshLab's library: points and colours) and CloudCompare 2.11.3 (points and colours).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flic_cli.io.atomic import atomic_write

__all__ = ["GROUND_RGB", "UNCLUSTERED_RGB", "cluster_rgb", "write_ply"]

#: Colour of ground points (light grey).
GROUND_RGB: tuple[int, int, int] = (170, 170, 170)
#: Colour of points in no cluster that are not ground (dark grey).
UNCLUSTERED_RGB: tuple[int, int, int] = (80, 80, 80)

_GOLDEN = 0.618033988749895


def cluster_rgb(cluster_ids: np.ndarray) -> np.ndarray:
    """A bright colour per cluster id, the same for an id in every frame and file.

    Hues follow the golden-ratio sequence (neighbouring ids get distant hues); saturation and
    value vary a little with the id so that ids with close hues still differ.

    Parameters
    ----------
    cluster_ids : (N,) integer ids (any value; 0 gets a colour like any other id).

    Returns
    -------
    (N, 3) uint8 RGB.
    """
    import matplotlib.colors

    ids = np.asarray(cluster_ids, dtype=np.int64)
    hsv = np.stack(
        [
            (ids * _GOLDEN) % 1.0,
            0.65 + 0.35 * ((ids * 7) % 3) / 2,
            0.80 + 0.20 * ((ids * 5) % 2),
        ],
        axis=-1,
    )
    return np.rint(matplotlib.colors.hsv_to_rgb(hsv) * 255).astype(np.uint8)


def write_ply(
    path: str | Path,
    points: np.ndarray,
    cluster_ids: np.ndarray,
    ground: np.ndarray | None = None,
) -> Path:
    """Write a frame as a binary little-endian PLY point cloud, atomically.

    Parameters
    ----------
    path : the ``.ply`` file to write.
    points : (N, 3) (or (N, >=3), extra columns ignored) coordinates in metres.
    cluster_ids : (N,) cluster ids in ``0..2**31-1``, 0 = none (negative values, e.g. DBSCAN's
        -1, are written as 0).
    ground : (N,) bool, the points the ground remover took (coloured :data:`GROUND_RGB`); None =
        no ground marked.

    Returns
    -------
    The written file.

    Raises
    ------
    ValueError
        When the shapes disagree, a coordinate is not finite or an id does not fit 32 bits.
    """
    from plyfile import PlyData, PlyElement

    pts = np.asarray(points)
    if pts.ndim != 2 or pts.shape[1] < 3:
        raise ValueError(f"points must have shape (N, 3), got {pts.shape}")
    n = pts.shape[0]
    ids = np.asarray(cluster_ids)
    if ids.shape != (n,) or not np.issubdtype(ids.dtype, np.integer):
        raise ValueError(f"cluster_ids must be ({n},) integers, got {ids.dtype} {ids.shape}")
    if ids.size and ids.max() > np.iinfo(np.int32).max:
        raise ValueError(f"cluster id {ids.max()} does not fit a 32-bit PLY int")
    xyz = pts[:, :3].astype(np.float32)
    if not np.isfinite(xyz).all():
        raise ValueError("points must have finite coordinates")
    ids = np.maximum(ids.astype(np.int64), 0).astype(np.int32)
    rgb = cluster_rgb(ids)
    rgb[ids == 0] = UNCLUSTERED_RGB
    if ground is not None:
        g = np.asarray(ground, dtype=bool)
        if g.shape != (n,):
            raise ValueError(f"ground must have shape ({n},), got {g.shape}")
        rgb[g] = GROUND_RGB
    vertex = np.empty(
        n,
        dtype=[
            ("x", "<f4"),
            ("y", "<f4"),
            ("z", "<f4"),
            ("cluster", "<i4"),
            ("red", "u1"),
            ("green", "u1"),
            ("blue", "u1"),
        ],
    )
    vertex["x"], vertex["y"], vertex["z"] = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    vertex["cluster"] = ids
    vertex["red"], vertex["green"], vertex["blue"] = rgb[:, 0], rgb[:, 1], rgb[:, 2]
    ply = PlyData(
        [PlyElement.describe(vertex, "vertex")],
        text=False,
        byte_order="<",
        comments=[
            "written by flic: x y z in metres (sensor frame), cluster = cluster id (0 = none)",
            f"colours: ground {GROUND_RGB}, unclustered {UNCLUSTERED_RGB}, clusters by id",
        ],
    )
    path = Path(path)
    with atomic_write(path) as tmp:
        ply.write(str(tmp))
    return path
