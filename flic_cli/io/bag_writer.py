"""Segmented frames out as ROS 2 bags: ``sensor_msgs/PointCloud2`` with ``x y z intensity
cluster`` (and ``label``), for RViz and Foxglove.

``flic segment BAG --export mcap`` (or ``--export bag``) writes one rosbag2 folder per run,
``<out>/<bag name>_flic/`` with its ``metadata.yaml`` and one ``.mcap`` (or sqlite3 ``.db3``)
file, through rosbags' writer. Every message keeps the input message's header stamp and frame
id, so that the clusters lie over the original recording in RViz or Foxglove (open the
``.mcap`` file itself in Foxglove; ``ros2 bag play <folder>`` for RViz).

Point layout (little-endian, 20 or 24 bytes per point):

====== ====== ======== ==========================================
field  offset type     meaning
====== ====== ======== ==========================================
x      0      FLOAT32  metres, the input's frame
y      4      FLOAT32
z      8      FLOAT32
intensity 12  FLOAT32  the input's intensity (0 when it has none)
cluster 16    UINT32   cluster id, 0 = none (ground, noise, small)
label  20     UINT32   semantic class (only with ``--semantics``)
====== ====== ======== ==========================================
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from flic_cli.errors import FlicInputError

#: ``--export`` name -> rosbags storage plugin name.
STORAGES = {"mcap": "MCAP", "bag": "SQLITE3"}

POINTCLOUD2 = "sensor_msgs/msg/PointCloud2"
FLOAT32, UINT32 = 7, 6


def cloud_layout(with_label: bool) -> np.dtype:
    """The structured dtype of the written points (see the module's table)."""
    names = ["x", "y", "z", "intensity", "cluster"] + (["label"] if with_label else [])
    formats = ["<f4"] * 4 + ["<u4"] * (2 if with_label else 1)
    return np.dtype({"names": names, "formats": formats})


class CloudBagWriter:
    """Write one PointCloud2 per frame into a new rosbag2 folder (use as a context manager).

    Parameters
    ----------
    path : the folder to create (it must not exist).
    storage : ``"mcap"`` or ``"bag"`` (sqlite3).
    topic : the topic to write (e.g. ``/flic/clusters``).
    with_label : also write a ``label`` field (semantic class).
    """

    def __init__(self, path: Path, storage: str, topic: str, with_label: bool = False) -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore

        if storage not in STORAGES:
            raise FlicInputError(None, f"--export {storage}: one of {', '.join(STORAGES)}")
        self.path = Path(path)
        self.topic = topic
        self.with_label = with_label
        self.dtype = cloud_layout(with_label)
        self._store = get_typestore(Stores.ROS2_HUMBLE)
        self._writer = Writer(
            self.path, version=9, storage_plugin=getattr(StoragePlugin, STORAGES[storage])
        )
        self._conn: Any = None
        self.messages = 0

    def __enter__(self) -> CloudBagWriter:
        self._writer.open()
        self._conn = self._writer.add_connection(self.topic, POINTCLOUD2, typestore=self._store)
        return self

    def __exit__(self, *exc: object) -> None:
        self._writer.close()

    def write(
        self,
        stamp_ns: int,
        frame_id: str,
        points: np.ndarray,
        cluster: np.ndarray,
        intensity: np.ndarray | None = None,
        label: np.ndarray | None = None,
    ) -> None:
        """Write one frame.

        Parameters
        ----------
        stamp_ns : header stamp (and bag time) in nanoseconds.
        frame_id : header frame id.
        points : (N, 3) float points in metres.
        cluster : (N,) cluster ids (>= 0).
        intensity : (N,) intensities, or None (written as 0).
        label : (N,) semantic classes (only when the writer has ``with_label``).
        """
        n = points.shape[0]
        cloud = np.zeros(n, dtype=self.dtype)
        cloud["x"], cloud["y"], cloud["z"] = points[:, 0], points[:, 1], points[:, 2]
        if intensity is not None:
            cloud["intensity"] = intensity
        cloud["cluster"] = cluster
        if self.with_label:
            cloud["label"] = 0 if label is None else label
        self._writer.write(self._conn, int(stamp_ns), self._serialize(stamp_ns, frame_id, cloud))
        self.messages += 1

    def _serialize(self, stamp_ns: int, frame_id: str, cloud: np.ndarray) -> bytes:
        t = self._store.types
        fields = [
            t["sensor_msgs/msg/PointField"](
                name=name,
                offset=int(self.dtype.fields[name][1]),
                datatype=FLOAT32 if self.dtype.fields[name][0].kind == "f" else UINT32,
                count=1,
            )
            for name in self.dtype.names
        ]
        header = t["std_msgs/msg/Header"](
            stamp=t["builtin_interfaces/msg/Time"](
                sec=int(stamp_ns // 1_000_000_000), nanosec=int(stamp_ns % 1_000_000_000)
            ),
            frame_id=frame_id,
        )
        msg = t[POINTCLOUD2](
            header=header,
            height=1,
            width=cloud.shape[0],
            fields=fields,
            is_bigendian=False,
            point_step=self.dtype.itemsize,
            row_step=self.dtype.itemsize * cloud.shape[0],
            data=cloud.view(np.uint8).reshape(-1),
            is_dense=True,
        )
        return bytes(self._store.serialize_cdr(msg, POINTCLOUD2))


def export_folder(out: Path, bag: Path, storage: str) -> Path:
    """Where ``--export mcap|bag`` of ``bag`` goes: ``<out>/<name>_flic_<storage>``."""
    name = bag.name if bag.is_dir() else bag.stem
    return Path(out) / f"{name}_flic_{storage}"
