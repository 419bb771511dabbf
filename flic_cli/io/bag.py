"""ROS 1 bags, ROS 2 bags (sqlite3 ``.db3`` or ``.mcap`` storage) and plain MCAP files, read
without ROS (the pure-Python ``rosbags`` package).

A bag is a DATA path like a dataset folder: ``recording.bag``, ``recording.mcap``, a rosbag2
folder (``metadata.yaml`` + storage files) or its ``.db3``. Its LiDAR topics are the frames'
"sequences" (``--topic`` or ``--sequences`` picks one; without, the bag must have exactly one);
every revolution on the topic is one frame, numbered from 0 in recording order. LiDAR topics:

- ``sensor_msgs/PointCloud2``: any field layout, offsets and endianness as the message
  declares them (:mod:`flic_cli.io.pointcloud2`). With a ``ring`` / ``channel`` field the rows
  are the beams and the columns the azimuth (the sensor's own image); an organised cloud
  (``height`` > 1) gives its rows; an unorganised cloud without ring field is projected like a
  SemanticKITTI scan (``[projection]``: rows recovered from the scan order, else spherical).
  One message = one frame.
- ``velodyne_msgs/VelodyneScan`` (one revolution of raw packets per message; ROS 2 bags do not
  store its definition, flic registers it), decoded by :mod:`flic_cli.io.velodyne`.
- ``ouster_ros/PacketMsg`` raw packets with the sensor's metadata JSON on a ``std_msgs/String``
  topic of the bag (``.../metadata``), decoded by :mod:`flic_cli.io.ouster`; one frame = the
  packets of one ``frame_id``.

The bag is read as a stream: the constructor lists the frames' times from the bag's own index
(ROS 1 connection index, sqlite3 ``messages`` table; MCAP storage and Ouster packets, whose
frames are frame ids, are read once for them) and reads the first revolution for the beams;
:meth:`BagDataset.load` reads one frame, continuing where the previous one ended when frames
are loaded in order (else it seeks by time). Memory does not grow with the bag's length.
"""

from __future__ import annotations

import json
import re
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from flic_cli.errors import FlicInputError
from flic_cli.io.base import Frame, FrameRef
from flic_cli.io.pointcloud2 import (
    INTENSITY_FIELDS,
    RING_FIELDS,
    Beams,
    cloud_array,
    estimate_beams,
    first_field,
    ring_image,
    xyz_of,
)
from flic_cli.io.semantickitti import export_path, write_cluster_prediction

FORMAT = "bag"
SUFFIXES = (".bag", ".mcap", ".db3")

POINTCLOUD2 = "sensor_msgs/msg/PointCloud2"
VELODYNE_SCAN = "velodyne_msgs/msg/VelodyneScan"
OUSTER_PACKET = "ouster_ros/msg/PacketMsg"
#: ouster-ros 0.11+ on ROS 2 names the same message ouster_sensor_msgs/msg/PacketMsg.
OUSTER_PACKET_2 = "ouster_sensor_msgs/msg/PacketMsg"
STRING = "std_msgs/msg/String"
#: Message types that carry LiDAR revolutions.
LIDAR_TYPES = (POINTCLOUD2, VELODYNE_SCAN, OUSTER_PACKET, OUSTER_PACKET_2)

#: Definitions of driver messages that ROS 2 bags do not store (rosbag2 metadata version < 8):
#: velodyne_msgs (ros-drivers/velodyne, also written by tier4/nebula), ouster_ros.
EXTRA_TYPES: dict[str, str] = {
    "velodyne_msgs/msg/VelodynePacket": "builtin_interfaces/Time stamp\nuint8[1206] data\n",
    "velodyne_msgs/msg/VelodyneScan": (
        "std_msgs/Header header\nvelodyne_msgs/VelodynePacket[] packets\n"
    ),
    "ouster_ros/msg/PacketMsg": "uint8[] buf\n",
    "ouster_sensor_msgs/msg/PacketMsg": "uint8[] buf\n",
}


def is_bag(path: Path) -> bool:
    """A ROS 1 ``.bag``, an ``.mcap`` or ``.db3`` file, or a rosbag2 folder."""
    path = Path(path)
    if path.is_file():
        return path.suffix in SUFFIXES
    return path.is_dir() and (path / "metadata.yaml").is_file()


def typestore() -> Any:
    """A rosbags typestore with ROS 2 Humble's messages and :data:`EXTRA_TYPES`."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types: dict[str, Any] = {}
    for name, text in EXTRA_TYPES.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


def _reader_path(path: Path) -> Path:
    """The path rosbags opens: a rosbag2 folder for its ``.db3`` when there is a metadata.yaml."""
    if path.suffix == ".db3" and (path.parent / "metadata.yaml").is_file():
        return path.parent
    return path


def open_reader(path: Path) -> Any:
    """An opened :class:`rosbags.highlevel.AnyReader` on ``path`` (close it, or use ``with``).

    Raises
    ------
    FlicInputError
        When rosbags is not installed, or the file is not a readable bag (truncated, corrupt).
    """
    try:
        from rosbags.highlevel import AnyReader
    except ImportError:  # pragma: no cover - a core dependency
        raise FlicInputError(path, "reading bags needs rosbags: pip install rosbags") from None
    reader = AnyReader([_reader_path(Path(path))], default_typestore=typestore())
    try:
        reader.open()
    except Exception as exc:  # rosbags raises its own error classes, and struct/OS errors
        raise FlicInputError(path, f"cannot be read as a bag ({_reason(exc)})") from None
    return reader


def _reason(exc: BaseException) -> str:
    text = " ".join(str(a) for a in exc.args) or type(exc).__name__
    return text.splitlines()[0][:200] if text else type(exc).__name__


@dataclass(frozen=True)
class TopicInfo:
    """One topic of a bag: its name, message type, message count, whether flic reads it."""

    topic: str
    msgtype: str
    count: int
    lidar: bool


def topics(path: str | Path) -> list[TopicInfo]:
    """Every topic of a bag with its type and message count, sorted by name.

    Raises
    ------
    FlicInputError
        When the bag cannot be read.
    """
    path = Path(path)
    reader = open_reader(path)
    try:
        found: dict[tuple[str, str], int] = {}
        for c in reader.connections:
            key = (c.topic, c.msgtype)
            found[key] = found.get(key, 0) + int(c.msgcount)
        lidar = {t for t, _ in _lidar_connections(reader, path)}
    finally:
        reader.close()
    return [TopicInfo(t, m, n, t in lidar) for (t, m), n in sorted(found.items())]


def _lidar_connections(reader: Any, path: Path) -> list[tuple[str, list[Any]]]:
    """``(topic, connections)`` of the LiDAR topics (Ouster packet topics whose first packet is
    an IMU packet, i.e. shorter than 1 kB, are not)."""
    by_topic: dict[str, list[Any]] = {}
    for c in reader.connections:
        if c.msgtype in LIDAR_TYPES:
            by_topic.setdefault(c.topic, []).append(c)
    out = []
    for topic, conns in sorted(by_topic.items()):
        if conns[0].msgtype in (OUSTER_PACKET, OUSTER_PACKET_2):
            first = next(reader.messages(connections=conns), None)
            if first is None or len(first[2]) < 1024:
                continue
        out.append((topic, conns))
    return out


def safe_name(topic: str) -> str:
    """A topic as a file name: ``/os_node0/lidar_packets`` -> ``os_node0_lidar_packets``."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", topic).strip("_") or "topic"


@dataclass
class BagFrame(Frame):
    """A frame read from a bag, with what an export needs besides the points.

    Attributes
    ----------
    stamp_ns : the message's header stamp in nanoseconds (the first packet's for Ouster packet
        frames).
    frame_id : the message's header frame id.
    intensity : (N,) float32 intensity (or reflectivity) of every point in ``points``, or None.
    """

    stamp_ns: int = 0
    frame_id: str = ""
    intensity: np.ndarray | None = None

    def export_fields(self) -> dict[str, Any]:
        """What :mod:`flic_cli.io.bag_writer` writes besides the points and clusters."""
        return {"stamp_ns": self.stamp_ns, "frame_id": self.frame_id, "intensity": self.intensity}


@dataclass(frozen=True)
class _Slot:
    """Where frame k lies in the bag: its messages' timestamps (first, last) and, for packet
    frames, its frame id."""

    start: int
    stop: int
    frame_id: int = -1
    skip: int = 0  # earlier messages of the topic with the same time (read past when seeking)


@dataclass
class _Cursor:
    """An open reader and its position (frames are read on from where the last one ended)."""

    reader: Any
    messages: Iterator[tuple[Any, int, bytes]] | None = None
    next_frame: int = -1
    pending: tuple[Any, int, bytes] | None = None


class BagDataset:
    """The LiDAR frames of one topic of a bag (implements :class:`flic_cli.io.base.Dataset`).

    Parameters
    ----------
    root : the bag (file or rosbag2 folder).
    sequences : topics to use (``["/velodyne_points"]``; the file-name form
        ``velodyne_points`` works too); only one topic per run. None = the only LiDAR topic.
    frames : ``(start, stop)`` revolution numbers on the topic (stop exclusive), None = all.
    require_labels : bags carry no labels: fails when True.

    Raises
    ------
    FlicInputError
        When the bag cannot be read, has no LiDAR topic, has several and none was chosen, the
        chosen topic does not exist or is not LiDAR, or the frame selection is empty.
    """

    format = FORMAT
    detect = staticmethod(is_bag)
    #: Predictions carry cluster ids only (no semantic class per point).
    point_semantics: ClassVar[bool] = False

    def __init__(
        self,
        root: str | Path,
        sequences: list[str] | None = None,
        frames: tuple[int | None, int | None] | None = None,
        require_labels: bool = False,
    ) -> None:
        self.root = Path(root)
        if require_labels:
            raise FlicInputError(self.root, "a bag has no ground-truth labels")
        reader = open_reader(self.root)
        self._cursor: _Cursor | None = None
        try:
            self.topic, conns = self._choose_topic(reader, sequences)
            self.msgtype = conns[0].msgtype
            self._conn_ids = {c.id for c in conns}
            self.sequence = safe_name(self.topic)
            self._is_ouster = self.msgtype in (OUSTER_PACKET, OUSTER_PACKET_2)
            self._meta = self._ouster_metadata(reader) if self._is_ouster else None
            self._frame_id = "os_sensor"
            self.partial_frames = 0
            self._slots = self._index(reader, conns)
            all_frames = len(self._slots)
            start, stop = frames or (None, None)
            sel = range(all_frames)[slice(start, stop)]
            if not sel:
                raise FlicInputError(
                    self.root,
                    f"topic {self.topic}: no frames in {start or 0}:{'' if stop is None else stop}"
                    f" (the topic has {all_frames})",
                )
            self._selected = list(sel)
            self.beams: Beams | None = None
            self.sensor_model: Any = None  # the SensorModel of packet topics
            self._velodyne: Any = None
            first = self._read_frame(reader, self._selected[0], conns)
            self.beams = self._beams_of(first)
        finally:
            reader.close()

    # -- the Dataset interface ------------------------------------------------------------

    def labelled(self) -> bool:
        """Bags carry no ground-truth labels."""
        return False

    def refs(self) -> list[FrameRef]:
        """Every selected revolution of the topic, in recording order."""
        return [FrameRef(self.sequence, k, self.root, None, FORMAT, k) for k in self._selected]

    def sensor(self, ref: FrameRef | None = None) -> Any:
        """The sensor model of a packet topic (Ouster metadata, velodyne-decoder's calibration;
        :class:`flic_cli.io.sensor.SensorModel`), None for PointCloud2 (see :attr:`beams`)."""
        return self.sensor_model

    def folders(self) -> list[Path]:
        """The bag's folder (outputs must not go inside a rosbag2 folder)."""
        return [self.root if self.root.is_dir() else self.root.parent]

    #: ``<out>/sequences/<topic>/predictions/XXXXXX.label``: one uint32 per point of the
    #: message as stored (cluster id in the upper 16 bits, the class in the lower); exports
    #: ``<out>/sequences/<topic>/<kind>/XXXXXX.<kind>`` (the SemanticKITTI layout)
    write_prediction = staticmethod(write_cluster_prediction)
    export_path = staticmethod(export_path)

    def load(self, ref: FrameRef) -> BagFrame:
        """Read revolution ``ref.frame`` of the topic.

        Raises
        ------
        FlicInputError
            Naming the bag and topic, when the messages cannot be read or decoded.
        """
        cursor = self._open_cursor()
        conns = [c for c in cursor.reader.connections if c.id in self._conn_ids]
        return self._read_frame(cursor.reader, ref.index, conns, cursor)

    # -- pickling: the open reader stays in its process -----------------------------------

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state["_cursor"] = None
        return state

    def close(self) -> None:
        """Close the reader that :meth:`load` opened (it is reopened on the next load)."""
        if self._cursor is not None:
            self._cursor.reader.close()
            self._cursor = None

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # noqa: BLE001 - never raise from a finaliser
            pass

    # -- inside ---------------------------------------------------------------------------

    def _open_cursor(self) -> _Cursor:
        if self._cursor is None:
            self._cursor = _Cursor(open_reader(self.root))
        return self._cursor

    def _choose_topic(self, reader: Any, sequences: list[str] | None) -> tuple[str, list[Any]]:
        lidar = _lidar_connections(reader, self.root)
        if sequences:
            if len(sequences) > 1:
                raise FlicInputError(
                    self.root, f"one topic at a time, got {len(sequences)}: {', '.join(sequences)}"
                )
            wanted = sequences[0]
            for topic, conns in lidar:
                if wanted in (topic, safe_name(topic), topic.lstrip("/")):
                    return topic, conns
            others = {c.topic: c.msgtype for c in reader.connections}
            if wanted in others or "/" + wanted.lstrip("/") in others:
                name = wanted if wanted in others else "/" + wanted.lstrip("/")
                if others[name] not in reader.typestore.types:
                    raise FlicInputError(
                        self.root,
                        f"topic {name}: the bag stores no message definition of {others[name]} "
                        "and flic knows none (flic reads "
                        f"{', '.join(LIDAR_TYPES)})",
                    )
                raise FlicInputError(
                    self.root,
                    f"topic {name}: {others[name]} is not a LiDAR message type flic reads "
                    f"({', '.join(LIDAR_TYPES)})",
                )
            raise FlicInputError(
                self.root,
                f"topic {wanted}: no such topic (LiDAR topics: "
                f"{', '.join(t for t, _ in lidar) or 'none'})",
            )
        if not lidar:
            listed = ", ".join(f"{c.topic} ({c.msgtype})" for c in reader.connections) or "none"
            raise FlicInputError(
                self.root,
                f"no LiDAR topic ({', '.join(LIDAR_TYPES)}); its topics: {listed}",
            )
        if len(lidar) > 1:
            raise FlicInputError(
                self.root,
                f"{len(lidar)} LiDAR topics, choose one with --topic: "
                + ", ".join(f"{t} ({c[0].msgtype})" for t, c in lidar),
            )
        return lidar[0]

    def _ouster_metadata(self, reader: Any) -> Any:
        """The sensor metadata JSON of an Ouster packet bag (its ``std_msgs/String`` topic
        named ``.../metadata``)."""
        conns = [
            c for c in reader.connections if c.msgtype == STRING and c.topic.endswith("metadata")
        ]
        from flic_cli.io import ouster

        for c, _, raw in reader.messages(connections=conns):
            text = str(self._deserialize(reader, raw, c).data)
            try:
                return ouster.OusterMeta.from_json(json.loads(text))
            except (json.JSONDecodeError, ouster.OusterDataError) as exc:
                raise FlicInputError(
                    self.root, f"topic {c.topic}: the Ouster metadata is not usable ({exc})"
                ) from None
        raise FlicInputError(
            self.root,
            f"topic {self.topic}: Ouster packets need the sensor metadata, and the bag has no "
            "std_msgs/String .../metadata topic",
        )

    def _deserialize(self, reader: Any, raw: bytes, conn: Any) -> Any:
        try:
            return reader.deserialize(raw, conn.msgtype)
        except KeyError:
            raise FlicInputError(
                self.root,
                f"topic {conn.topic}: the bag has no definition of {conn.msgtype} and flic does "
                "not know it",
            ) from None
        except Exception as exc:  # a truncated or corrupt message
            raise FlicInputError(
                self.root, f"topic {conn.topic}: message cannot be decoded ({_reason(exc)})"
            ) from None

    def _messages(
        self, reader: Any, conns: list[Any], start: int | None = None, stop: int | None = None
    ) -> Iterator[tuple[Any, int, bytes]]:
        """The topic's raw messages, bad storage reported as a FlicInputError."""
        it = reader.messages(connections=conns, start=start, stop=stop)
        while True:
            try:
                item = next(it)
            except StopIteration:
                return
            except FlicInputError:
                raise
            except Exception as exc:
                raise FlicInputError(
                    self.root, f"topic {self.topic}: bag is truncated or corrupt ({_reason(exc)})"
                ) from None
            yield item

    def _index(self, reader: Any, conns: list[Any]) -> list[_Slot]:
        """Where every revolution lies: one slot per message, or per complete Ouster frame
        (packets of one frame id that fill every column; partial ones at the start and end of a
        recording are left out, as the pcap reader does)."""
        if not self._is_ouster:
            times = index_times(reader, conns, self.root)
            if times is None:  # no index to read: the topic's messages, read once
                times = [t for _, t, _ in self._messages(reader, conns)]
            slots, last, same = [], None, 0
            for t in times:
                same = same + 1 if t == last else 0
                slots.append(_Slot(t, t, skip=same))
                last = t
            return slots
        from flic_cli.io import ouster

        meta = self._meta
        slots: list[_Slot] = []
        bufs: list[bytes] = []
        current, first, last = -1, 0, 0

        def finish() -> None:
            try:
                (frame,) = ouster.decode_frames(bufs, meta)
            except ouster.OusterDataError as exc:
                raise FlicInputError(self.root, f"topic {self.topic}: {exc}") from None
            if frame.complete:
                slots.append(_Slot(first, last, current))
            else:
                self.partial_frames += 1

        for c, t, raw in self._messages(reader, conns):
            buf = _packet_buf(self._deserialize(reader, raw, c))
            try:
                ouster.check_packet(buf, meta)
            except ouster.OusterDataError as exc:
                raise FlicInputError(self.root, f"topic {self.topic}: {exc}") from None
            fid = ouster._frame_id(buf, meta)
            if bufs and fid != current:
                finish()
                bufs = []
            if not bufs:
                current, first = fid, t
            bufs.append(buf)
            last = t
        if bufs:
            finish()
        return slots

    def _read_frame(
        self, reader: Any, k: int, conns: list[Any], cursor: _Cursor | None = None
    ) -> BagFrame:
        ref = FrameRef(self.sequence, k, self.root, None, FORMAT, k)
        slot = self._slots[k]
        if cursor is not None and cursor.next_frame == k and cursor.messages is not None:
            it = cursor.messages
        else:
            it = self._messages(reader, conns, slot.start, None)
            for _ in range(slot.skip):  # messages of the same time before this one
                next(it, None)
            if cursor is not None:
                cursor.messages, cursor.pending = it, None
        if self._is_ouster:
            frame = self._ouster_frame(reader, ref, slot, it, cursor)
        else:
            item = cursor.pending if cursor is not None and cursor.pending else None
            if item is None:
                item = next(it, None)
            if cursor is not None:
                cursor.pending = None
            if item is None or item[1] != slot.start:
                raise FlicInputError(self.root, f"topic {self.topic}: message {k} is missing")
            if self.msgtype == POINTCLOUD2:
                frame = self._cloud_frame(ref, self._deserialize(reader, item[2], item[0]))
            else:
                scan = _scan_of(self._deserialize(reader, item[2], item[0]))
                frame = self._velodyne_frame(ref, *scan)
        if cursor is not None:
            cursor.next_frame = k + 1
        return frame

    # -- the three message kinds ----------------------------------------------------------

    def _cloud_frame(self, ref: FrameRef, msg: Any) -> BagFrame:
        try:
            cloud = cloud_array(msg)
        except ValueError as exc:
            raise FlicInputError(self.root, f"topic {self.topic}: PointCloud2 {exc}") from None
        xyz = xyz_of(cloud, self.root, self.topic)
        names = cloud.dtype.names or ()
        ring_name = first_field(names, RING_FIELDS)
        intensity_name = first_field(names, INTENSITY_FIELDS)
        organised = int(msg.height) > 1
        if ring_name is not None:
            ring = cloud[ring_name]
        elif organised:
            ring = np.arange(xyz.shape[0], dtype=np.int64) // int(msg.width)
        else:
            ring = None
        header = msg.header
        stamp = int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)
        intensity = None if intensity_name is None else cloud[intensity_name]
        if self.beams is None and ring is not None:  # the first frame: the sensor's beams
            width = int(msg.width) if organised and ring_name is None else None
            how = f"ring field {ring_name!r}" if ring_name else f"organised rows ({msg.height})"
            self.beams = estimate_beams(xyz, ring, width, how)
        return self._frame(ref, xyz, ring, intensity, stamp, str(header.frame_id))

    def _velodyne_frame(
        self, ref: FrameRef, stamp_ns: int, frame_id: str, packets: list[tuple[float, bytes]]
    ) -> BagFrame:
        """A VelodyneScan message (one revolution of packets) decoded by
        :mod:`flic_cli.io.velodyne`: its sensor model (velodyne-decoder's calibration) and
        image (:func:`flic_cli.io.velodyne.scan_image`)."""
        from flic_cli.io import velodyne

        if not packets:
            raise FlicInputError(self.root, f"topic {self.topic}: message {ref.frame} is empty")
        if self._velodyne is None:
            self._velodyne = velodyne.detect_sensor([packets[0][1]])
        try:
            cloud = _velodyne_points(self._velodyne, packets)
        except (RuntimeError, ValueError) as exc:
            raise FlicInputError(
                self.root, f"topic {self.topic}: Velodyne packets cannot be decoded ({exc})"
            ) from None
        if self.sensor_model is None:
            self.sensor_model = self._velodyne.sensor_model(int(cloud["column"].max()) + 1)
        image, xyz = velodyne.scan_image(cloud, self.sensor_model)
        intensity = np.asarray(cloud["intensity"], dtype=np.float32)
        return BagFrame(
            ref, xyz, None, image, stamp_ns=stamp_ns, frame_id=frame_id, intensity=intensity
        )

    def _ouster_frame(
        self, reader: Any, ref: FrameRef, slot: _Slot, it: Iterator, cursor: _Cursor | None
    ) -> BagFrame:
        """The packets of the slot's frame id decoded by :mod:`flic_cli.io.ouster` (its
        destaggered image and the sensor's geometry); intensity = reflectivity."""
        from flic_cli.io import ouster

        meta = self._meta
        bufs = []
        pending = cursor.pending if cursor is not None else None
        while True:
            item = pending if pending is not None else next(it, None)
            pending = None
            if item is None or item[1] > slot.stop:
                pending = item
                break
            buf = _packet_buf(self._deserialize(reader, item[2], item[0]))
            if ouster._frame_id(buf, meta) == slot.frame_id:
                bufs.append(buf)
        if cursor is not None:
            cursor.pending = pending
        if not bufs:
            raise FlicInputError(self.root, f"topic {self.topic}: frame {ref.frame} has no packets")
        try:
            (frame,) = ouster.decode_frames(bufs, meta, ("reflectivity",))
        except (ouster.OusterDataError, ValueError) as exc:
            raise FlicInputError(
                self.root, f"topic {self.topic}: frame {ref.frame} cannot be decoded ({exc})"
            ) from None
        image, points = ouster.frame_image(frame, meta)
        refl = ouster.destagger(frame.fields["reflectivity"], meta.pixel_shift)
        intensity = refl.reshape(-1)[image.point_pixel].astype(np.float32)
        if self.sensor_model is None:
            self.sensor_model = meta.sensor_model()
        return BagFrame(
            ref, points, None, image, stamp_ns=slot.start, frame_id=self._frame_id,
            intensity=intensity,
        )  # fmt: skip

    def _frame(
        self,
        ref: FrameRef,
        xyz: np.ndarray,
        ring: np.ndarray | None,
        intensity: np.ndarray | None,
        stamp: int,
        frame_id: str,
    ) -> BagFrame:
        """A frame from its points as stored: the ring image when the beams are known, else
        the finite points for the pipeline's projection."""
        if ring is not None and self.beams is not None:
            image, kept = ring_image(xyz, ring, self.beams)
        else:
            image, kept = None, np.isfinite(xyz).all(axis=1) & (np.abs(xyz).sum(axis=1) > 0)
        all_kept = bool(kept.all())
        points = xyz if all_kept else xyz[kept]
        inten = None
        if intensity is not None:
            inten = np.asarray(intensity, dtype=np.float32)
            inten = inten if all_kept else inten[kept]
        return BagFrame(
            ref, points, None, image, finite=None if all_kept else kept, stamp_ns=stamp,
            frame_id=frame_id, intensity=inten,
        )  # fmt: skip

    def _beams_of(self, first: BagFrame) -> Beams | None:
        if self.beams is None and first.image is None and self.msgtype == POINTCLOUD2:
            warnings.warn(
                f"{self.root}: topic {self.topic}: PointCloud2 without ring field and not "
                "organised: rows are estimated by the [projection] settings",
                stacklevel=3,
            )
        return self.beams

    def describe(self) -> dict[str, Any]:
        """What ``flic info`` shows about the chosen topic: topic, type, frames, beams x
        columns and where the beams came from."""
        out: dict[str, Any] = {"topic": self.topic, "type": self.msgtype}
        out["frames"] = f"{len(self._slots)} revolutions"
        if self.partial_frames:
            out["frames"] += f" ({self.partial_frames} partial ones at the ends left out)"
        if self.sensor_model is not None:
            out.update(self.sensor_model.describe())
        elif self.beams is not None:
            b = self.beams
            out["beams x columns"] = f"{b.rows} x {b.width}"
            out["beam angles from"] = f"{b.source}: median elevation per ring of frame 0"
        else:
            out["beams x columns"] = "unknown: projected by the [projection] settings"
        return out


def index_times(reader: Any, conns: list[Any], path: Path) -> list[int] | None:
    """The bag times of a topic's messages from the bag's own index, without reading them:
    a ROS 1 bag's connection index (rosbags keeps it), a sqlite3 ``.db3``'s ``messages`` table.
    None where there is no such index (MCAP storage, compressed files): the caller reads the
    messages."""
    readers = getattr(reader, "readers", [])
    if readers and all(hasattr(r, "indexes") for r in readers):  # rosbags' ROS 1 reader
        ids = {c.id for c in conns}
        try:
            return sorted(i.time for r in readers for cid in ids for i in r.indexes.get(cid, ()))
        except (AttributeError, TypeError):
            return None
    files = [path] if path.suffix == ".db3" else sorted(path.glob("*.db3")) if path.is_dir() else []
    if not files or any(conns[0].msgtype != c.msgtype for c in conns):
        return None
    import sqlite3

    times: list[int] = []
    for f in files:
        try:
            con = sqlite3.connect(f"file:{f}?mode=ro", uri=True)
            try:
                rows = con.execute(
                    "select m.timestamp from messages m join topics t on m.topic_id = t.id "
                    "where t.name = ? order by m.timestamp",
                    (conns[0].topic,),
                ).fetchall()
            finally:
                con.close()
        except sqlite3.Error:
            return None
        times += [int(r[0]) for r in rows]
    return sorted(times)


def _scan_of(msg: Any) -> tuple[int, str, list[tuple[float, bytes]]]:
    """A deserialised VelodyneScan as ``(stamp ns, frame id, [(packet time s, 1206 bytes)])``.

    The packets go to velodyne-decoder as ``bytes``: built from numpy arrays, its packet objects
    convert element by element (66 ms per 151-packet revolution against 2 ms)."""
    stamp = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
    packets = [
        (int(p.stamp.sec) + int(p.stamp.nanosec) * 1e-9, np.asarray(p.data, np.uint8).tobytes())
        for p in msg.packets
    ]
    return stamp, str(msg.header.frame_id), packets


def _velodyne_points(sensor: Any, packets: list[tuple[float, bytes]]) -> np.ndarray:
    """One revolution of Velodyne packets ``(host time s, 1206 bytes)`` as velodyne-decoder's
    structured points (x y z intensity time column ring return_type), decoded whole (a
    VelodyneScan is one revolution already: no cut at an angle) with the sensor's config
    (:class:`flic_cli.io.velodyne.VelodyneSensor`)."""
    import velodyne_decoder as vd

    decoder = vd.ScanDecoder(sensor.config)
    _, cloud = decoder.decode([vd.VelodynePacket(t, data) for t, data in packets], True)
    return cloud


def _packet_buf(msg: Any) -> bytes:
    """The packet of an ``ouster_ros/PacketMsg``: its ``buf`` (ouster-ros 0.10+ prefixes 4 bytes
    of length to nothing; older bags store the packet alone)."""
    return np.asarray(msg.buf, dtype=np.uint8).tobytes()


__all__ = [
    "EXTRA_TYPES",
    "LIDAR_TYPES",
    "BagDataset",
    "BagFrame",
    "TopicInfo",
    "is_bag",
    "open_reader",
    "safe_name",
    "topics",
    "typestore",
]


def info_lines(path: str | Path, topic: str | None = None) -> tuple[list[str], bool]:
    """``flic info``'s bag part: every topic with its type and message count (LiDAR ones
    marked).

    Returns
    -------
    lines : the table (and, without a LiDAR topic to describe, why).
    describe : whether a LiDAR topic is chosen (``topic``, or the bag has exactly one), so that
        its frames and sensor can be described.

    Raises
    ------
    FlicInputError
        When the bag cannot be read.
    """
    found = topics(path)
    width = max((len(t.topic) for t in found), default=5)
    lines = [f"{'topic':<{width}}  {'messages':>8}  type"]
    for t in found:
        mark = "  (LiDAR)" if t.lidar else ""
        lines.append(f"{t.topic:<{width}}  {t.count:>8}  {t.msgtype}{mark}")
    lidar = [t for t in found if t.lidar]
    if topic is None and len(lidar) != 1:
        if lidar:
            lines.append(f"{len(lidar)} LiDAR topics: choose one with --topic for its sensor")
        else:
            lines.append("no LiDAR topic flic reads (" + ", ".join(LIDAR_TYPES) + ")")
        return lines, False
    return lines, True
