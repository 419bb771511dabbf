"""Velodyne lidar packets and pcap recordings, decoded by velodyne-decoder.

The decoding works on UDP payloads (``bytes``), so that other containers (ROS bags) reuse it:
:func:`decode_scans` turns data packets into revolutions (velodyne-decoder's ``StreamDecoder``:
a scan is one full turn from its first packet), :func:`scan_image` makes one into a range image:
row ``H - 1 - ring`` (velodyne-decoder's ``ring`` numbers the lasers by elevation, 0 = lowest),
column = the firing (velodyne-decoder's ``column``) shifted so that column 0 looks backwards.
The beams' elevation, azimuth offsets and origin offsets come from velodyne-decoder's built-in
calibration of the model (the model is read from the packets' factory byte; HDL-64E, which has
none, through velodyne-decoder's own detection and its calibration in the stream).

Supported: every model velodyne-decoder 3 decodes (VLP-16, Puck Hi-Res, VLP-32C, HDL-32E,
HDL-64E S1/S2/S3, VLS-128, Alpha Prime); tested on the VLP-16 recording of the shared data.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import njit

from flic_cli.errors import FlicInputError
from flic_cli.io.base import Frame, FrameRef
from flic_cli.io.rings import nearest_pixels, pixel_image
from flic_cli.io.sensor import FileInfo, SensorFileDataset, SensorModel
from flic_cli.range_image import RangeImage

FORMAT = "velodyne"
PACKET_SIZE = 1206
"""Bytes of a Velodyne data packet (12 blocks of 100 bytes, time stamp, factory bytes)."""
DATA_PORT = 2368

#: Factory byte (the packet's last byte) -> velodyne-decoder model name, beams.
FACTORY_MODELS: dict[int, tuple[str, int]] = {
    0x21: ("HDL32E", 32),
    0x22: ("VLP16", 16),
    0x23: ("PuckLite", 16),
    0x24: ("PuckHiRes", 16),
    0x28: ("VLP32C", 32),
    0xA1: ("VLS128", 128),
}
#: Return mode byte -> name.
RETURN_MODES = {0x37: "strongest", 0x38: "last", 0x39: "dual"}


def _vd():  # noqa: ANN202
    try:
        import velodyne_decoder
    except ImportError:  # pragma: no cover - a core dependency
        raise FlicInputError(
            None, "reading Velodyne packets needs velodyne-decoder (pip install velodyne-decoder)"
        ) from None
    return velodyne_decoder


def is_data_packet(payload: bytes) -> bool:
    """True for a 1206-byte packet whose blocks start with a Velodyne block flag."""
    return len(payload) == PACKET_SIZE and payload[:2] in (b"\xff\xee", b"\xff\xdd")


@dataclass(frozen=True, eq=False)
class VelodyneSensor:
    """The model and calibration a recording was decoded with.

    Attributes
    ----------
    model : velodyne-decoder's model name (e.g. ``"VLP16"``).
    return_mode : ``"strongest"``, ``"last"``, ``"dual"`` or ``"unknown"``.
    calibration_text : velodyne-decoder calibration (YAML text), None = its built-in one for
        the model. (Text, so that the object pickles for worker processes.)
    assumed : the model is assumed (packets without product id, a calibration given), not read
        from the packets.
    """

    model: str
    return_mode: str
    calibration_text: str | None = None
    assumed: bool = False

    @property
    def config(self):  # noqa: ANN201
        """A velodyne-decoder ``Config`` for this model and calibration."""
        vd = _vd()
        calib = (
            None
            if self.calibration_text is None
            else vd.Calibration.from_string(self.calibration_text)
        )
        return vd.Config(model=getattr(vd.Model, self.model), calibration=calib)

    @property
    def name(self) -> str:
        """``"Velodyne VLP16"``."""
        return f"Velodyne {self.model}"

    def calibration(self) -> dict[str, np.ndarray]:
        """The calibration's per-laser ``vert_correction``, ``rot_correction`` (radians),
        ``vert_offset_correction`` and ``dist_correction`` (metres), by laser id (0 where the
        calibration leaves a key out), read from its YAML with PyYAML (velodyne-decoder's own
        dependency)."""
        import yaml

        vd = _vd()
        text = self.calibration_text
        if text is None:
            text = vd.Calibration.default_calibs[getattr(vd.Model, self.model)].to_string()
        lasers = sorted(yaml.safe_load(text)["lasers"], key=lambda laser: int(laser["laser_id"]))
        keys = ("vert_correction", "rot_correction", "vert_offset_correction", "dist_correction")
        return {k: np.array([float(laser.get(k, 0.0)) for laser in lasers]) for k in keys}

    def sensor_model(self, columns: int) -> SensorModel:
        """Beam angles from velodyne-decoder's calibration, rows sorted top to bottom."""
        cal = self.calibration()
        order = np.argsort(cal["vert_correction"])[::-1]  # top beam first
        offsets = cal["vert_offset_correction"]
        notes = [f"return mode {self.return_mode}"]
        if self.assumed:
            notes.append(
                f"model {self.model} assumed (no product id in the packets), with the "
                "--calibration given"
            )
        elif self.calibration_text is not None:
            notes.append("calibration: --calibration, or the one the packets carry (HDL-64E)")
        if np.any(offsets):
            notes.append(
                "vertical beam origin offsets "
                f"{1000 * offsets.min():+.1f} .. {1000 * offsets.max():+.1f} mm (calibration)"
            )
        return SensorModel(
            name=self.name,
            elevation=cal["vert_correction"][order].astype(np.float64),
            azimuth_offset=cal["rot_correction"][order].astype(np.float64),
            columns=columns,
            angles_from="decoder",
            columns_from="firings in the revolution (velodyne-decoder's column)",
            notes=tuple(notes),
        )


def read_calibration(path: str | Path) -> str:
    """A velodyne-decoder calibration file (its YAML: ``distance_resolution`` and per-laser
    ``vert_correction``, ``rot_correction``, ... in radians and metres), as text.

    Raises
    ------
    FlicInputError
        When velodyne-decoder cannot read it.
    """
    try:
        return _vd().Calibration.read(str(path)).to_string()
    except Exception as exc:  # noqa: BLE001 - the binding raises RuntimeError / YAML errors
        raise FlicInputError(
            path, f"is not a velodyne-decoder calibration file ({type(exc).__name__}: {exc})"
        ) from None


HDL64E_HINT = (
    "an HDL-64E (its packets carry no product id) is decoded with its per-unit calibration: "
    "give --calibration FILE, velodyne-decoder's YAML (e.g. its bundled "
    "HDL-64E_S3-VeloView.yml, or one made from the sensor's db.xml)"
)


def detect_sensor(
    payloads: list[bytes], path: object = None, calibration: str | None = None
) -> VelodyneSensor:
    """The model (from the factory byte) and return mode of a recording's data packets.

    Parameters
    ----------
    payloads : data packets (the first is read).
    path : a pcap for velodyne-decoder's HDL-64E detection (an HDL-64E S2/S3 sends its
        calibration in the status bytes of its packets; velodyne-decoder reads it from there).
    calibration : velodyne-decoder calibration text (:func:`read_calibration`, the
        ``calibration`` reader option): replaces the built-in one of a model with a product id;
        for packets without one, the HDL-64E S3 is assumed with this calibration.

    Raises
    ------
    FlicInputError
        When the model is unknown and cannot be detected (naming ``--calibration``).
    """
    vd = _vd()
    first = payloads[0]
    factory, mode = first[1205], first[1204]
    ret = RETURN_MODES.get(mode, "unknown")
    if factory in FACTORY_MODELS:
        return VelodyneSensor(FACTORY_MODELS[factory][0], ret, calibration)
    if calibration is not None:
        return VelodyneSensor("HDL64E_S3", ret, calibration, assumed=True)
    why = f"factory byte 0x{factory:02x}"
    if path is not None:
        try:
            model, calib = vd.hdl64e.detect_hdl64e(str(path))
        except (ValueError, RuntimeError, KeyError) as exc:
            why = f"no calibration in its status bytes: {exc}"
        else:
            if model is not None:
                return VelodyneSensor(str(model).split(".")[-1], ret, calib.to_string())
    raise FlicInputError(path, f"unknown Velodyne model ({why}); {HDL64E_HINT}")


@dataclass(frozen=True, eq=False)
class VelodyneScan:
    """One revolution as velodyne-decoder decodes it.

    Attributes
    ----------
    stamp : time stamp of the scan (seconds; velodyne-decoder's host time).
    points : (N,) structured array with fields x, y, z (m), intensity, time, column, ring,
        return_type.
    complete : True for a full turn; False for the remainder at the end of a stream.
    first_packet, last_packet : indices (into the payloads) of the scan's first packet and of the
        packet whose arrival completed it.
    """

    stamp: float
    points: np.ndarray
    complete: bool
    first_packet: int
    last_packet: int


def decode_scans(
    packets: Iterable[tuple[float, bytes | tuple[int, ...]]],
    sensor: VelodyneSensor,
    remainder: bool = True,
) -> Iterator[VelodyneScan]:
    """Decode ``(time stamp, payload)`` data packets into revolutions.

    Parameters
    ----------
    packets : data packets (1206 bytes, or their 1206 byte values as a tuple of ints, which
        velodyne-decoder's binding converts fastest; others are skipped) with their capture
        time stamps.
    sensor : the model to decode with (:func:`detect_sensor`).
    remainder : also yield the incomplete scan left at the end (``complete = False``).
    """
    vd = _vd()
    decoder = vd.StreamDecoder(sensor.config)
    start = 0
    i = -1
    for i, (stamp, payload) in enumerate(packets):
        if len(payload) != PACKET_SIZE:
            continue
        result = decoder.decode(float(stamp), payload, True)
        if result is not None:  # this packet completed the scan: the next one starts after it
            yield VelodyneScan(_stamp(result[0]), result[1], True, start, i)
            start = i + 1
    if remainder:
        result = decoder.finish(True)
        if result is not None and len(result[1]):
            yield VelodyneScan(_stamp(result[0]), result[1], False, start, i)


_SCAN_DECODERS: dict[tuple[str, str | None], object] = {}


def _scan_decoder(sensor: VelodyneSensor):  # noqa: ANN202
    """A velodyne-decoder ``ScanDecoder`` for the sensor, made once per process (making one
    takes 0.2 ms)."""
    key = (sensor.model, sensor.calibration_text)
    if key not in _SCAN_DECODERS:
        _SCAN_DECODERS[key] = _vd().ScanDecoder(sensor.config)
    return _SCAN_DECODERS[key]


_PACKET_BYTES = struct.Struct(f"{PACKET_SIZE}B")


def decode_packets(
    sensor: VelodyneSensor, stamps: list[float], payloads: list[bytes]
) -> tuple[float, np.ndarray]:
    """One revolution's data packets decoded whole by velodyne-decoder's ``ScanDecoder`` (one
    C++ call, no cut at an angle).

    Parameters
    ----------
    sensor : the model to decode with (:func:`detect_sensor`).
    stamps : host time stamp of every packet, seconds.
    payloads : the packets, 1206 bytes each.

    Returns
    -------
    stamp : the scan's time stamp, seconds.
    points : velodyne-decoder's structured points (see :class:`VelodyneScan`).

    Notes
    -----
    velodyne-decoder's binding takes a packet as a sequence of 1,206 ints and converts a
    ``bytes`` object through a temporary tuple; handing it the tuples ``struct.iter_unpack``
    makes in one C loop over the joined payloads is the fastest input it has (0.41 against
    0.49 ms for the 77 packets of a VLP-16 turn, minimum of 300 interleaved runs).
    """
    vd = _vd()
    packets = vd.PacketVector(
        [
            vd.VelodynePacket(t, p)
            for t, p in zip(stamps, _PACKET_BYTES.iter_unpack(b"".join(payloads)), strict=True)
        ]
    )
    stamp, points = _scan_decoder(sensor).decode(packets, True)
    return _stamp(stamp), points


def _stamp(pair: object) -> float:
    return float(getattr(pair, "host", pair))


def scan_image(points: np.ndarray, model: SensorModel) -> tuple[RangeImage, np.ndarray]:
    """The range image of a decoded scan and its points.

    Columns: velodyne-decoder's firing index, rolled so that the first firing lands at the column
    whose nominal azimuth (+pi at column 0, decreasing) is nearest its own; ``W`` = the firings
    in this revolution (so no two firings share a column). Rows and pixels as
    :func:`flic_cli.io.rings.ring_image` makes them (its kernel, called from this one).

    Parameters
    ----------
    points : velodyne-decoder's scan as its structured array (``as_pcl_structs=True``: x, y, z,
        intensity, time, column, ring, return_type).
    model : the sensor model (its ``elevation`` gives the rows).

    Returns
    -------
    image : RangeImage (``projection == "rings"``), one pixel per point, the nearest return of
        a pixel (dual return mode) giving its range.
    points : (N, 3) float32 xyz in metres, in the decoder's order (``image.point_pixel[i]`` is
        the pixel of point ``i``).
    """
    h = model.elevation.size
    xyz, ranges, counts, pix, z, width = _scan_pixels(points, h)
    return pixel_image(ranges, counts, pix, z, model.elevation, width), xyz


@njit(cache=True)
def _scan_pixels(
    points: np.ndarray, h: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """xyz and :func:`flic_cli.io.rings.nearest_pixels` of a decoded scan, W = the firings
    (``column.max() + 1``), the firings rolled so that the first one's mean azimuth lands in
    its nominal column."""
    n = points.shape[0]
    xyz = np.empty((n, 3), dtype=np.float32)
    column = np.empty(n, dtype=np.int64)
    ring = np.empty(n, dtype=np.int64)
    lo, hi = 1 << 30, -1
    for i in range(n):
        p = points[i]
        xyz[i, 0], xyz[i, 1], xyz[i, 2] = p.x, p.y, p.z
        c = np.int64(p.column)
        column[i], ring[i] = c, np.int64(p.ring)
        lo = min(lo, c)
        hi = max(hi, c)
    width = hi + 1 if n else 1
    sx, sy = 0.0, 0.0
    for i in range(n):
        if column[i] == lo:
            sx += xyz[i, 0]
            sy += xyz[i, 1]
    shift = 0
    if n:
        shift = np.int64(np.floor((np.pi - np.arctan2(sy, sx)) / (2.0 * np.pi) * width)) - lo
    ranges, counts, pix, z = nearest_pixels(xyz, ring, column, h, width, shift)
    return xyz, ranges, counts, pix, z, width


# ---------------------------------------------------------------------------------------------
# pcap recordings
# ---------------------------------------------------------------------------------------------


KEEP_PACKETS_MAX_BYTES = 512 * 2**20
"""Data packets of a pcap up to this many bytes in all are kept at open as velodyne-decoder's
packet objects, one ``PacketVector`` per revolution (about the packets' own size in memory), so
that a frame load only decodes and projects; a larger capture is read from the file per frame,
its packets converted again (0.4 ms per VLP-16 turn)."""


@dataclass
class _PcapState:
    """What a frame load needs: where the packets lie, and (up to
    :data:`KEEP_PACKETS_MAX_BYTES`) each revolution's packets ready for velodyne-decoder."""

    index: object  # UdpIndex
    sensor: VelodyneSensor
    data: np.ndarray  # indices (into index) of the data packets
    scans: list[tuple[int, int, int]]  # per complete scan: first, last data packet, points
    packets: list | None = None  # per complete scan: its PacketVector; None = read the file

    def __getstate__(self) -> dict:
        """Pickled without the packet objects (velodyne-decoder's do not pickle): a worker
        process reads its frames from the file."""
        return {**self.__dict__, "packets": None}


class VelodynePcapDataset(SensorFileDataset):
    """A Velodyne pcap, or a folder of them (implements :class:`flic_cli.io.base.Dataset`).

    Any pcap without an Ouster metadata JSON beside it is taken for a Velodyne one (so that a
    capture without lidar packets is reported as such). A frame is one complete revolution as
    velodyne-decoder cuts them; the remainder at the end of the capture is left out (``flic
    info`` lists it). A frame's points are velodyne-decoder's returns, in its order.

    Opening decodes the capture once (to find the revolutions) and keeps each revolution's
    packets as velodyne-decoder's packet objects (up to :data:`KEEP_PACKETS_MAX_BYTES`); a
    frame load decodes them again (one C++ call) and makes the range image.
    """

    format = FORMAT
    suffixes = (".pcap", ".pcapng")
    reader_options = ("calibration",)

    @classmethod
    def accepts(cls, path: Path) -> bool:
        """A pcap file that is not an Ouster recording."""
        from flic_cli.io.ouster import OusterPcapDataset
        from flic_cli.io.pcap import is_capture

        if not (path.is_file() and path.name.lower().endswith(cls.suffixes)):
            return False
        return is_capture(path) and not OusterPcapDataset.accepts(path)

    def _open(self, path: Path) -> FileInfo:
        from flic_cli.io.pcap import index_udp, iter_payloads, read_payloads

        index = index_udp(path)
        data = np.flatnonzero(index.size == PACKET_SIZE)
        first = next(
            (p for p in read_payloads(index, data[:64]) if is_data_packet(p)), None
        )  # the model is read from the first data packet
        if first is None:
            sizes = sorted(set(index.size.tolist()))[:6]
            raise FlicInputError(
                path,
                f"holds no lidar packets: no Velodyne data packet ({PACKET_SIZE} bytes, port "
                f"{DATA_PORT}) among its {index.size.size} UDP packets"
                + (f" (sizes {', '.join(map(str, sizes))} bytes)" if sizes else "")
                + ", and no Ouster metadata JSON beside it",
            )
        given = self.options.get("calibration")
        sensor = detect_sensor([first], path, None if given is None else read_calibration(given))
        kept: list[int] = []
        keep_packets = data.size * PACKET_SIZE <= KEEP_PACKETS_MAX_BYTES
        vd = _vd()
        pending: list = []  # the packet objects of the revolution being decoded

        def packets() -> Iterator[tuple[float, tuple[int, ...]]]:  # read a chunk at a time
            stamps = index.time[data].tolist()
            for k, payload in enumerate(iter_payloads(index, data)):
                if is_data_packet(payload):
                    kept.append(k)
                    values = _PACKET_BYTES.unpack(payload)  # the binding's fastest input
                    if keep_packets:
                        pending.append(vd.VelodynePacket(stamps[k], values))
                    yield stamps[k], values

        scans, partial = [], []
        vectors: list = []
        width = 0
        for scan in decode_scans(packets(), sensor):  # one scan decoded at once
            if scan.complete:
                if not scans:  # the sensor model's columns: the first revolution's firings
                    width = int(scan.points["column"].max()) + 1 if len(scan.points) else 1
                scans.append((scan.first_packet, scan.last_packet, len(scan.points)))
                if keep_packets:  # pending holds exactly this scan's packets here
                    vectors.append(vd.PacketVector(pending))
                    pending.clear()
            else:
                partial.append(f"remainder of {len(scan.points):,} points")
        pending.clear()
        data = data[np.array(kept, dtype=np.int64)]
        if not scans:
            raise FlicInputError(
                path, f"has no complete revolution ({'; '.join(partial) or 'no points'})"
            )
        return FileInfo(
            path,
            len(scans),
            sensor.sensor_model(width),
            np.array([s[2] for s in scans], dtype=np.int64),
            partial,
            _PcapState(index, sensor, data, scans, vectors if keep_packets else None),
        )

    @staticmethod
    def _scan(state: _PcapState, k: int, path: Path) -> VelodyneScan:
        """Revolution ``k``: velodyne-decoder's ``ScanDecoder`` over exactly the packets the
        stream decoder put into it when the file was opened (the same points, checked by
        ``test_velodyne_load_equals_one_decoding_pass``), one C++ call."""
        from flic_cli.io.pcap import read_payloads

        first, last, n = state.scans[k]
        if state.packets is not None:  # kept at open
            pair, points = _scan_decoder(state.sensor).decode(state.packets[k], True)
            stamp = _stamp(pair)
        else:
            which = state.data[first : last + 1]
            payloads = read_payloads(state.index, which)  # type: ignore[arg-type]
            stamps = state.index.time[which].tolist()  # type: ignore[attr-defined]
            stamp, points = decode_packets(state.sensor, stamps, payloads)
        if len(points) != n:
            raise FlicInputError(path, f"frame {k} decodes differently than when it was opened")
        return VelodyneScan(stamp, points, True, first, last)

    def _load(self, info: FileInfo, k: int) -> Frame:
        state: _PcapState = info.state  # type: ignore[assignment]
        scan = self._scan(state, k, info.path)
        image, points = scan_image(scan.points, info.sensor)
        ref = FrameRef(self.sequence_name(info.path), k, info.path, None, FORMAT, index=k)
        return Frame(ref, points, None, image)
