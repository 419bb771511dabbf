"""Ouster lidar packets and recordings: a pcap with its JSON metadata.

The packet decoder works on UDP payloads (``bytes``), so that other containers (ROS bags, see
``flic_cli/io/bags``) reuse it: :meth:`OusterMeta.from_json` reads the sensor metadata,
:func:`decode_frames` turns a stream of lidar packets into revolutions (:class:`OusterFrame`),
:func:`frame_image` makes one into a range image with the points of its valid pixels, computed
with the sensor's own geometry.

Packet formats (Ouster's "Sensor Data" documentation, firmware 2.x/3.x; decoded here with numpy
views, no per-pixel Python):

- ``LEGACY``: 16 columns per packet; a column = 16-byte header (time stamp u64, measurement id
  u16, frame id u16, encoder count u32), H channels of 12 bytes (range u32, low 20 bits, mm;
  reflectivity u16; signal u16; near-IR u16; unused u16) and a 4-byte status (0xFFFFFFFF =
  valid).
- ``RNG19_RFL8_SIG16_NIR16``: 32-byte packet header (packet type u16, frame id u16, ...), 16
  columns of a 12-byte header (time stamp u64, measurement id u16, status u16, bit 0 = valid) and
  H channels of 12 bytes (range u32, low 19 bits, mm; reflectivity u8; reserved u8; signal u16;
  near-IR u16; reserved u16), 32-byte footer.
- ``RNG15_RFL8_NIR8`` (low data rate): as above with 4-byte channels (range u16, low 15 bits, in
  units of 8 mm; reflectivity u8; near-IR u8).
- ``RNG19_RFL8_SIG16_NIR16_DUAL`` (dual return): as ``RNG19_RFL8_SIG16_NIR16`` with 16-byte
  channels: first return's range (u32, low 19 bits, mm) with its reflectivity in byte 3, the
  second return's range (u32 at byte 4, low 19 bits) with its reflectivity in byte 7, signal u16
  and second signal u16 (bytes 8, 10), near-IR u16 (byte 12). flic reads one return per pixel:
  the first (the strongest, in Ouster's definition) by default, the second with the ``return``
  reader option (``--return 2``).

The layouts are those of ouster-sdk's field tables (``ouster_core/src/parsing.cpp``); other
profiles (the FUSA / zone-monitoring ones, RGB) are refused with the list of these.

Metadata: both JSON layouts (firmware <= 2.3 "flat", and the nested ``sensor_info`` /
``lidar_data_format`` / ``beam_intrinsics`` one of later firmware and of ouster-sdk). Fields
that are missing are defaulted as ouster-sdk 1.0 defaults them (``default_data_format``,
``default_lidar_origin_to_beam_origin``; see :data:`OusterMeta.defaulted`).

Geometry (ouster-sdk's ``make_xyz_lut``, the documented formula): for the pixel of beam ``i`` in
measurement column ``m`` of ``W``, encoder angle ``te = 2 pi (1 - m / W)``, beam azimuth
``ta = -azimuth_deg[i]`` and altitude ``phi = altitude_deg[i]`` (radians),
``x = (r - n) cos(te + ta) cos(phi) + b cos(te)``,
``y = (r - n) sin(te + ta) cos(phi) + b sin(te)``,
``z = (r - n) sin(phi) + bz``, with ``b, bz`` the beam-to-lidar translation and ``n`` its length;
then ``lidar_to_sensor_transform`` gives the sensor frame (x forward, y left, z up).
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
from numba import njit

from flic_cli.errors import FlicInputError
from flic_cli.io.base import Frame, FrameRef
from flic_cli.io.sensor import FileInfo, SensorFileDataset, SensorModel
from flic_cli.range_image import RangeImage

FORMAT = "ouster"

#: Lidar packet profiles: ``name -> (packet header bytes, column header bytes, channel bytes,
#: packet footer bytes)``.
PROFILES: dict[str, tuple[int, int, int, int]] = {
    "LEGACY": (0, 16, 12, 0),  # + 4-byte status at the end of each column
    "RNG19_RFL8_SIG16_NIR16": (32, 12, 12, 32),
    "RNG15_RFL8_NIR8": (32, 12, 4, 32),
    "RNG19_RFL8_SIG16_NIR16_DUAL": (32, 12, 16, 32),
}

#: Channel fields per profile: ``name -> (byte offset in the channel, dtype, bit mask (0 =
#: all), multiplier)``; a second return's fields end in ``2``.
CHANNEL_FIELDS: dict[str, dict[str, tuple[int, str, int, int]]] = {
    "LEGACY": {
        "range": (0, "<u4", 0xFFFFF, 1),
        "reflectivity": (4, "<u2", 0, 1),
        "signal": (6, "<u2", 0, 1),
        "near_ir": (8, "<u2", 0, 1),
    },
    "RNG19_RFL8_SIG16_NIR16": {
        "range": (0, "<u4", 0x7FFFF, 1),
        "reflectivity": (4, "u1", 0, 1),
        "signal": (6, "<u2", 0, 1),
        "near_ir": (8, "<u2", 0, 1),
    },
    "RNG15_RFL8_NIR8": {
        "range": (0, "<u2", 0x7FFF, 8),
        "reflectivity": (2, "u1", 0, 1),
        "near_ir": (3, "u1", 0, 1),
    },
    "RNG19_RFL8_SIG16_NIR16_DUAL": {
        "range": (0, "<u4", 0x7FFFF, 1),
        "reflectivity": (3, "u1", 0, 1),
        "range2": (4, "<u4", 0x7FFFF, 1),
        "reflectivity2": (7, "u1", 0, 1),
        "signal": (8, "<u2", 0, 1),
        "signal2": (10, "<u2", 0, 1),
        "near_ir": (12, "<u2", 0, 1),
    },
}

#: ouster-sdk's default ``lidar_to_sensor_transform`` (a half turn about z, 36.18 mm up).
DEFAULT_LIDAR_TO_SENSOR = np.array(
    [[-1, 0, 0, 0], [0, -1, 0, 0], [0, 0, 1, 36.18], [0, 0, 0, 1]], dtype=np.float64
)


class OusterDataError(ValueError):
    """Packets that do not match the metadata, or metadata that cannot be used."""


def packet_size(profile: str, beams: int, columns_per_packet: int = 16) -> int:
    """Bytes of one lidar packet of a profile."""
    head, col_head, chan, foot = PROFILES[profile]
    status = 4 if profile == "LEGACY" else 0
    return head + columns_per_packet * (col_head + beams * chan + status) + foot


def _default_pixel_shift(columns: int) -> list[int]:
    """ouster-sdk's ``default_data_format`` pixel shift for 64 beams (legacy metadata)."""
    base = {512: [9, 6, 3, 0], 1024: [18, 12, 6, 0], 2048: [36, 24, 12, 0], 4096: [72, 48, 24, 0]}
    if columns not in base:
        raise OusterDataError(f"lidar_mode with {columns} columns has no default data format")
    return base[columns] * 16


def _default_beam_origin_mm(prod_line: str) -> float:
    """ouster-sdk's ``default_lidar_origin_to_beam_origin`` (mm) for a product line."""
    for prefix, mm in (("OS-0-", 27.67), ("OS-1-", 15.806), ("OS-2-", 13.762)):
        if prod_line.startswith(prefix):
            return mm
    return 12.163  # gen 1


@dataclass(frozen=True, eq=False)
class OusterMeta:
    """An Ouster sensor's metadata, as far as decoding and geometry need it.

    Attributes
    ----------
    prod_line : e.g. ``"OS-2-128"`` (``""`` when the metadata does not say).
    serial, firmware : as the metadata says (``""`` when absent).
    lidar_mode : e.g. ``"1024x10"``.
    beams : pixels per column (H).
    columns : columns per frame (W).
    columns_per_packet : columns in one lidar packet.
    profile : the lidar packet profile (a key of :data:`PROFILES`).
    altitude_deg, azimuth_deg : (H,) float64 beam altitude and azimuth angles in degrees.
    pixel_shift : (H,) int64 ``pixel_shift_by_row`` (destaggering).
    column_window : ``(first, last)`` measurement ids the sensor sends.
    beam_to_lidar : (4, 4) float64 beam-to-lidar transform (translation in mm).
    lidar_to_sensor : (4, 4) float64 lidar-to-sensor transform (translation in mm).
    udp_port_lidar : the lidar data's UDP port, or None when the metadata does not say.
    defaulted : names of the fields that were missing and defaulted as ouster-sdk does.
    return_index : which return a pixel's range (and fields) come from: 1, or 2 for the second
        return of a dual-return profile (not part of the metadata: the ``return`` reader
        option, see :meth:`with_return`).
    """

    prod_line: str
    serial: str
    firmware: str
    lidar_mode: str
    beams: int
    columns: int
    columns_per_packet: int
    profile: str
    altitude_deg: np.ndarray
    azimuth_deg: np.ndarray
    pixel_shift: np.ndarray
    column_window: tuple[int, int]
    beam_to_lidar: np.ndarray
    lidar_to_sensor: np.ndarray
    udp_port_lidar: int | None = None
    defaulted: tuple[str, ...] = field(default=())
    return_index: int = 1

    def with_return(self, index: int) -> OusterMeta:
        """This metadata reading return ``index`` (1 or 2) of every pixel.

        Raises
        ------
        OusterDataError
            When the profile has no such return.
        """
        returns = 2 if "range2" in CHANNEL_FIELDS[self.profile] else 1
        if index not in range(1, returns + 1):
            raise OusterDataError(
                f"profile {self.profile} has {returns} return{'s' if returns > 1 else ''} per "
                f"pixel: --return {index} asks for another"
            )
        return dataclasses.replace(self, return_index=int(index))

    def field_name(self, name: str) -> str:
        """The channel field ``name`` (``"range"``, ``"reflectivity"``, ...) of the return read:
        ``"range2"`` for the second."""
        second = f"{name}2"
        return second if self.return_index == 2 and second in CHANNEL_FIELDS[self.profile] else name

    @classmethod
    def from_json(cls, meta: dict) -> OusterMeta:
        """Read metadata from its parsed JSON (flat or nested layout).

        Raises
        ------
        OusterDataError
            When the beam angles or the lidar mode are missing or inconsistent.
        """
        if not isinstance(meta, dict):
            raise OusterDataError("the metadata is not a JSON object")
        info = meta.get("sensor_info", meta)
        fmt = meta.get("lidar_data_format", meta.get("data_format"))
        intr = meta.get("beam_intrinsics", meta)
        config = meta.get("config_params", meta)
        lidar_intr = meta.get("lidar_intrinsics", meta)
        defaulted: list[str] = []
        try:
            alt = np.asarray(intr["beam_altitude_angles"], dtype=np.float64)
            azi = np.asarray(intr["beam_azimuth_angles"], dtype=np.float64)
        except (KeyError, TypeError, ValueError):
            raise OusterDataError(
                "has no beam_altitude_angles / beam_azimuth_angles (not Ouster metadata)"
            ) from None
        mode = str(config.get("lidar_mode", meta.get("lidar_mode", "")))
        try:
            mode_cols = int(mode.split("x")[0])
        except ValueError:
            raise OusterDataError(f"has lidar_mode {mode!r}, expected e.g. '1024x10'") from None
        if alt.ndim != 1 or alt.shape != azi.shape or alt.size == 0:
            raise OusterDataError(
                f"has {alt.size} altitude and {azi.size} azimuth angles, expected one per beam"
            )
        if fmt is None:
            defaulted.append("data_format")
            fmt = {
                "pixels_per_column": 64,
                "columns_per_packet": 16,
                "columns_per_frame": mode_cols,
                "pixel_shift_by_row": _default_pixel_shift(mode_cols),
                "column_window": [0, mode_cols - 1],
                "udp_profile_lidar": "LEGACY",
            }
        beams = int(fmt.get("pixels_per_column", alt.size))
        columns = int(fmt.get("columns_per_frame", mode_cols))
        profile = str(fmt.get("udp_profile_lidar", config.get("udp_profile_lidar", "LEGACY")))
        if profile not in PROFILES:
            raise OusterDataError(
                f"has packet profile {profile!r}; supported: {', '.join(PROFILES)}"
            )
        shift = np.asarray(fmt.get("pixel_shift_by_row", []), dtype=np.int64)
        if beams != alt.size or shift.size != beams:
            raise OusterDataError(
                f"declares {beams} pixels per column but has {alt.size} beam angles and "
                f"{shift.size} pixel shifts"
            )
        if columns != mode_cols:
            raise OusterDataError(f"declares {columns} columns per frame but lidar_mode {mode!r}")
        window = fmt.get("column_window", [0, columns - 1])
        prod_line = str(info.get("prod_line", ""))
        if "beam_to_lidar_transform" in intr:
            b2l = np.asarray(intr["beam_to_lidar_transform"], dtype=np.float64).reshape(4, 4)
        else:
            b2l = np.eye(4)
            if "lidar_origin_to_beam_origin_mm" in intr:
                b2l[0, 3] = float(intr["lidar_origin_to_beam_origin_mm"])
            else:
                defaulted.append("lidar_origin_to_beam_origin_mm")
                b2l[0, 3] = _default_beam_origin_mm(prod_line)
        if "lidar_to_sensor_transform" in lidar_intr:
            l2s = np.asarray(lidar_intr["lidar_to_sensor_transform"], dtype=np.float64)
            l2s = l2s.reshape(4, 4)
        else:
            defaulted.append("lidar_to_sensor_transform")
            l2s = DEFAULT_LIDAR_TO_SENSOR.copy()
        port = config.get("udp_port_lidar")
        return cls(
            prod_line=prod_line,
            serial=str(info.get("prod_sn", info.get("serial_no", ""))),
            firmware=str(info.get("build_rev", info.get("image_rev", ""))),
            lidar_mode=mode,
            beams=beams,
            columns=columns,
            columns_per_packet=int(fmt.get("columns_per_packet", 16)),
            profile=profile,
            altitude_deg=alt,
            azimuth_deg=azi,
            pixel_shift=shift,
            column_window=(int(window[0]), int(window[1])),
            beam_to_lidar=b2l,
            lidar_to_sensor=l2s,
            udp_port_lidar=int(port) if port not in (None, "", 0) else None,
            defaulted=tuple(defaulted),
        )

    @property
    def packet_size(self) -> int:
        """Bytes of one lidar packet."""
        return packet_size(self.profile, self.beams, self.columns_per_packet)

    @property
    def name(self) -> str:
        """``"Ouster OS-2-128"`` (or ``"Ouster (N beams)"`` without a product line)."""
        return f"Ouster {self.prod_line}" if self.prod_line else f"Ouster ({self.beams} beams)"

    @cached_property
    def azimuth_offset(self) -> np.ndarray:
        """(H,) azimuth of every beam in the destaggered image relative to its column's centre
        as :class:`flic_cli.range_image.RangeImage` places it (radians): the destaggered
        column ``c`` of beam ``i`` holds measurement ``c - shift[i]``, whose direction lies at
        encoder angle ``2 pi (1 - (c - shift[i]) / W)`` minus the beam's azimuth, turned by
        the half turn of ``lidar_to_sensor_transform``; the column's centre is
        ``pi - (c + 0.5) 2 pi / W``. (The beam origin offset is left out: it shifts the points,
        not the direction, by under 3 cm.)"""
        w = self.columns
        turn = float(np.arctan2(self.lidar_to_sensor[1, 0], self.lidar_to_sensor[0, 0]))
        off = 2 * np.pi * self.pixel_shift / w - np.radians(self.azimuth_deg) + np.pi / w
        off = off + turn - np.pi  # the default transform turns by pi: offset as above
        return np.angle(np.exp(1j * off))

    def sensor_model(self) -> SensorModel:
        """The range image's sensor model: beam angles from the metadata.

        ``azimuth_offset`` is each beam's azimuth in the destaggered image relative to the
        column centre :class:`flic_cli.range_image.RangeImage` assumes (radians).
        """
        w = self.columns
        offset = self.azimuth_offset
        notes = []
        if self.defaulted:
            notes.append("defaulted as ouster-sdk does: " + ", ".join(self.defaulted))
        notes.append(f"packet profile {self.profile}, lidar mode {self.lidar_mode}")
        return SensorModel(
            name=self.name,
            elevation=np.radians(self.altitude_deg),
            azimuth_offset=offset,
            columns=w,
            angles_from="metadata",
            beam_origin_mm=float(np.hypot(self.beam_to_lidar[0, 3], self.beam_to_lidar[2, 3])),
            columns_from=f"metadata (lidar_mode {self.lidar_mode})",
            notes=tuple(notes),
        )

    @cached_property
    def xyz_lut(self) -> tuple[np.ndarray, np.ndarray]:
        """``(direction, offset)``, each (H, W, 3) float32 in the DESTAGGERED layout: the sensor
        frame point of a pixel is ``direction * range_mm + offset`` (metres), as ouster-sdk's
        ``make_xyz_lut`` computes it for the staggered scan."""
        h, w = self.beams, self.columns
        m = np.arange(w, dtype=np.float64)
        encoder = (2.0 * np.pi - m * (2.0 * np.pi / w))[None, :].repeat(h, 0)
        azimuth = (-np.radians(self.azimuth_deg))[:, None]
        altitude = np.radians(self.altitude_deg)[:, None]
        b2l = self.beam_to_lidar
        n = b2l[0, 3] if b2l[2, 3] == 0 else float(np.hypot(b2l[0, 3], b2l[2, 3]))
        d = np.empty((h, w, 3))
        d[..., 0] = np.cos(encoder + azimuth) * np.cos(altitude)
        d[..., 1] = np.sin(encoder + azimuth) * np.cos(altitude)
        d[..., 2] = np.broadcast_to(np.sin(altitude), (h, w))
        o = np.empty((h, w, 3))
        o[..., 0] = np.cos(encoder) * b2l[0, 3] - d[..., 0] * n
        o[..., 1] = np.sin(encoder) * b2l[0, 3] - d[..., 1] * n
        o[..., 2] = -d[..., 2] * n + b2l[2, 3]
        rot = self.lidar_to_sensor[:3, :3]
        trans = self.lidar_to_sensor[:3, 3]
        d = d @ rot.T
        o = o @ rot.T + trans
        d *= 0.001
        o *= 0.001
        return (
            np.ascontiguousarray(destagger(d, self.pixel_shift), dtype=np.float32),
            np.ascontiguousarray(destagger(o, self.pixel_shift), dtype=np.float32),
        )


def read_meta(path: str | Path) -> OusterMeta:
    """Read an Ouster metadata JSON file.

    Raises
    ------
    FlicInputError
        When the file cannot be read, is not JSON, or not usable Ouster metadata.
    """
    from flic_cli.io.atomic import read_text

    try:
        meta = json.loads(read_text(path))
    except json.JSONDecodeError as exc:
        raise FlicInputError(path, f"is not valid JSON ({exc.msg}, line {exc.lineno})") from None
    try:
        return OusterMeta.from_json(meta)
    except OusterDataError as exc:
        raise FlicInputError(path, str(exc)) from None


def destagger(field: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """Destagger an (H, W, ...) field: row ``i`` rolled right by ``shift[i]`` columns, as
    ouster-sdk's ``destagger`` does (``out[i, (m + shift[i]) % W] = field[i, m]``)."""
    w = field.shape[1]
    cols = (np.arange(w)[None, :] - np.asarray(shift)[:, None]) % w
    idx = cols.reshape(cols.shape + (1,) * (field.ndim - 2))
    return np.take_along_axis(field, idx, axis=1)


@dataclass(frozen=True, eq=False)
class OusterFrame:
    """One revolution of packets, STAGGERED (column = measurement id).

    Attributes
    ----------
    frame_id : the packets' frame id.
    range_mm : (H, W) uint32 range in millimetres, 0 = no return or column not received.
    columns : (W,) bool, True for the columns received with valid status.
    fields : further (H, W) channel fields when asked for (``"reflectivity"``, ``"signal"``,
        ``"near_ir"``; those the profile has).
    packets : the number of consecutive packets the frame was assembled from.
    """

    frame_id: int
    range_mm: np.ndarray
    columns: np.ndarray
    fields: dict[str, np.ndarray] = field(default_factory=dict)
    packets: int = 0

    @property
    def complete(self) -> bool:
        """True when the revolution's first and last columns were received (a whole turn)."""
        return bool(self.columns[0] and self.columns[-1])

    @property
    def valid(self) -> int:
        """Number of pixels with a return (range > 0)."""
        return int(np.count_nonzero(self.range_mm))


def _frame_id(payload: bytes, meta: OusterMeta) -> int:
    off = 10 if meta.profile == "LEGACY" else 2
    return int.from_bytes(payload[off : off + 2], "little")


def _decode(batch: np.ndarray, meta: OusterMeta, fields: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Decode (P, packet_size) uint8 packets: measurement ids and status (P, C), the channel
    ``fields`` of the return read (P, C, H; see :data:`CHANNEL_FIELDS`)."""
    head, col_head, chan, foot = PROFILES[meta.profile]
    h, c = meta.beams, meta.columns_per_packet
    status_bytes = 4 if meta.profile == "LEGACY" else 0
    col_size = col_head + h * chan + status_bytes
    cols = batch[:, head : head + c * col_size].reshape(-1, c, col_size)
    mid = cols[:, :, 8:10].copy().view("<u2")[..., 0]
    if meta.profile == "LEGACY":
        valid = cols[:, :, col_size - 4 :].copy().view("<u4")[..., 0] == 0xFFFFFFFF
    else:
        valid = (cols[:, :, 10] & 1).astype(bool)
    ch = cols[:, :, col_head : col_head + h * chan].reshape(-1, c, h, chan)
    out = {"measurement_id": mid, "valid": valid}
    layout = CHANNEL_FIELDS[meta.profile]
    for name in fields:
        if meta.field_name(name) in layout:
            o, dt, mask, scale = layout[meta.field_name(name)]
            size = np.dtype(dt).itemsize
            value = ch[..., o : o + size].copy().view(dt)[..., 0]
            if mask:
                value &= np.array(mask, dtype=value.dtype)
            out[name] = value if scale == 1 else value.astype(np.uint32) * np.uint32(scale)
    return out


def check_packet(payload: bytes, meta: OusterMeta) -> None:
    """Raise :class:`OusterDataError` when a lidar packet's size does not fit the metadata,
    naming the profile and beam count it would fit."""
    size = len(payload)
    if size == meta.packet_size:
        return
    fits = [
        f"{p} with {b} beams"
        for p in PROFILES
        for b in (16, 32, 64, 128)
        if packet_size(p, b, meta.columns_per_packet) == size
    ]
    hint = f" (that size fits {' or '.join(fits)})" if fits else ""
    raise OusterDataError(
        f"lidar packets are {size} bytes, but the metadata's profile {meta.profile} with "
        f"{meta.beams} beams makes {meta.packet_size}-byte packets{hint}: the metadata does not "
        "match the recording"
    )


def decode_frames(
    payloads: Iterable[bytes], meta: OusterMeta, fields: tuple[str, ...] = ()
) -> Iterator[OusterFrame]:
    """Group lidar packets into revolutions (by frame id) and decode them.

    Parameters
    ----------
    payloads : the lidar packets' UDP payloads, in arrival order.
    meta : the sensor's metadata.
    fields : further channel fields to decode (``"reflectivity"``, ``"signal"``, ``"near_ir"``).

    Yields
    ------
    OusterFrame, one per frame id run (the first and last may be partial: see
    :attr:`OusterFrame.complete`).

    Raises
    ------
    OusterDataError
        When a packet's size does not match the metadata (profile, beams) or a measurement id
        lies beyond the metadata's columns.
    """
    batch: list[bytes] = []
    current = -1
    for payload in payloads:
        check_packet(payload, meta)
        fid = _frame_id(payload, meta)
        if batch and fid != current:
            yield _assemble(batch, current, meta, fields)
            batch = []
        current = fid
        batch.append(payload)
    if batch:
        yield _assemble(batch, current, meta, fields)


def _assemble(
    batch: list[bytes], frame_id: int, meta: OusterMeta, fields: tuple[str, ...]
) -> OusterFrame:
    buf = np.frombuffer(b"".join(batch), dtype=np.uint8)
    head, col_head, chan, _ = PROFILES[meta.profile]
    offset, _, mask, scale = CHANNEL_FIELDS[meta.profile][meta.field_name("range")]
    h, w = meta.beams, meta.columns
    out = np.zeros((h, w), dtype=np.uint32)
    columns = np.zeros(w, dtype=np.bool_)
    # every profile's packets, columns and channels are whole 4-byte words, and every range
    # field starts a word: read them as little-endian uint32 words
    bad = _decode_ranges(
        buf.view("<u4"), len(batch), meta.packet_size // 4, head // 4, col_head // 4, chan // 4,
        offset // 4, meta.columns_per_packet, meta.profile == "LEGACY", mask, scale, out, columns,
    )  # fmt: skip
    if bad >= 0:
        raise OusterDataError(
            f"a packet holds measurement id {bad}, beyond the {meta.columns} columns "
            f"of the metadata's lidar mode {meta.lidar_mode}: the metadata does not match the "
            "recording"
        )
    extra = {}
    if fields:
        dec = _decode(buf.reshape(len(batch), meta.packet_size), meta, fields)
        mid = dec["measurement_id"].reshape(-1)
        valid = dec["valid"].reshape(-1)
        good = mid[valid]
        for name in fields:
            if name in dec:
                f = dec[name].reshape(-1, h)
                img = np.zeros((h, w), dtype=f.dtype)
                img[:, good] = f[valid].T
                extra[name] = img
    return OusterFrame(frame_id, out, columns, extra, len(batch))


@njit(cache=True)
def _decode_ranges(
    words: np.ndarray,
    n_packets: int,
    size: int,
    head: int,
    col_head: int,
    chan: int,
    field: int,
    cols: int,
    legacy: bool,
    mask: int,
    scale: int,
    out: np.ndarray,
    columns: np.ndarray,
) -> int:
    """Fill the staggered (H, W) range image ``out`` (mm) and the received-column mask from
    ``n_packets`` packets given as uint32 words (every size and offset in words: packet, packet
    header, column header, channel, the range's word in the channel); range = ``(word & mask)
    * scale``. Returns -1, or a measurement id beyond W (then stops)."""
    h, w = out.shape
    col_size = col_head + chan * h + (1 if legacy else 0)
    m32 = np.uint32(mask)
    s32 = np.uint32(scale)
    for p in range(n_packets):
        for c in range(cols):
            base = p * size + head + c * col_size
            mid = np.int64(words[base + 2] & 0xFFFF)
            if legacy:
                ok = words[base + col_size - 1] == np.uint32(0xFFFFFFFF)
            else:
                ok = ((words[base + 2] >> 16) & 1) == 1
            if not ok:
                continue
            if mid >= w:
                return mid
            columns[mid] = True
            o = base + col_head + field
            for i in range(h):
                out[i, mid] = (words[o + chan * i] & m32) * s32
    return -1


def frame_image(frame: OusterFrame, meta: OusterMeta) -> tuple[RangeImage, np.ndarray]:
    """The destaggered range image of a revolution and the points of its valid pixels.

    Returns
    -------
    image : RangeImage, (H, W) ranges in metres (row 0 = beam 0, the top one), rows at the beams'
        altitude angles; its ``point_pixel`` lists the valid pixels in row-major order.
    points : (N, 3) float32 sensor-frame point of every valid pixel, in the order of
        ``image.point_pixel``, with the sensor's geometry (:attr:`OusterMeta.xyz_lut`).
    """
    direction, offset = meta.xyz_lut
    ranges, pix, counts, points = _image_points(frame.range_mm, meta.pixel_shift, direction, offset)
    image = RangeImage(
        ranges, np.radians(meta.altitude_deg), pix, "native", counts,
        azimuth_offset=meta.azimuth_offset, one_point_per_pixel=True,
    )  # fmt: skip
    return image, points


@njit(cache=True)
def _image_points(
    range_mm: np.ndarray, shift: np.ndarray, direction: np.ndarray, offset: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Destagger a staggered (H, W) range image (mm) into metres and compute the valid pixels'
    flat indices, point counts (0/1) and points (``direction * r + offset``)."""
    h, w = range_mm.shape
    n = 0
    for i in range(h):
        for m in range(w):
            n += range_mm[i, m] > 0
    ranges = np.zeros((h, w), dtype=np.float32)
    counts = np.zeros((h, w), dtype=np.int32)
    pix = np.empty(n, dtype=np.int64)
    pts = np.empty((n, 3), dtype=np.float32)
    j = 0
    for i in range(h):
        s = shift[i] % w
        for c in range(w):
            m = c - s
            if m < 0:
                m += w
            r = range_mm[i, m]
            if r > 0:
                rf = np.float64(r)
                ranges[i, c] = np.float32(rf * 0.001)
                counts[i, c] = 1
                pix[j] = i * w + c
                for k in range(3):
                    pts[j, k] = np.float32(
                        np.float64(direction[i, c, k]) * rf + np.float64(offset[i, c, k])
                    )
                j += 1
    return ranges, pix, counts, pts


# ---------------------------------------------------------------------------------------------
# pcap recordings
# ---------------------------------------------------------------------------------------------


def _is_ouster_json(path: Path) -> bool:
    try:
        with open(path, "rb") as f:
            return b"beam_altitude_angles" in f.read(1 << 20)
    except OSError:
        return False


def find_meta(pcap: Path) -> Path | None:
    """The metadata JSON of an Ouster pcap: ``<name>.json`` beside it, else the one Ouster JSON
    of its folder whose name shares the longest prefix with the pcap's (at least up to the
    first ``_``, e.g. ``OS-1-64_...``); None when there is none.

    Raises
    ------
    FlicInputError
        When two JSON files fit equally well.
    """
    same = pcap.with_suffix(".json")
    if same.is_file() and _is_ouster_json(same):
        return same
    stem = pcap.stem
    best: list[tuple[int, Path]] = []
    for cand in sorted(pcap.parent.glob("*.json")):
        n = len(os.path.commonprefix([stem, cand.stem]))
        if "_" in stem and n < stem.index("_") + 1:
            continue
        if n and _is_ouster_json(cand):
            best.append((n, cand))
    if not best:
        return None
    best.sort(key=lambda t: -t[0])
    if len(best) > 1 and best[0][0] == best[1][0]:
        raise FlicInputError(
            pcap,
            f"has no {same.name}, and {best[0][1].name} and {best[1][1].name} fit its name "
            f"equally well: name its metadata {same.name}",
        )
    return best[0][1]


@dataclass
class _PcapState:
    index: object  # UdpIndex
    meta: OusterMeta
    packets: list[np.ndarray]  # per complete frame: indices into index


class OusterPcapDataset(SensorFileDataset):
    """An Ouster pcap with its metadata JSON, or a folder of them (implements
    :class:`flic_cli.io.base.Dataset`).

    A frame is one complete revolution (first and last column received); revolutions cut off
    at the start or end of the capture are left out (``flic info`` lists them). The frame's
    points are its valid pixels (range > 0) in row-major order of the destaggered image.
    """

    format = FORMAT
    suffixes = (".pcap", ".pcapng")
    reader_options = ("return",)

    @classmethod
    def accepts(cls, path: Path) -> bool:
        """A pcap file with an Ouster metadata JSON beside it (:func:`find_meta`)."""
        from flic_cli.io.pcap import is_capture

        if not (path.is_file() and path.name.lower().endswith(cls.suffixes)):
            return False
        try:
            return is_capture(path) and find_meta(path) is not None
        except FlicInputError:
            return True  # ambiguous metadata: ours, and opening says why

    def _open(self, path: Path) -> FileInfo:
        from flic_cli.io.pcap import index_udp, iter_payloads

        meta_path = find_meta(path)
        if meta_path is None:
            raise FlicInputError(path, "has no Ouster metadata JSON beside it")
        meta = read_meta(meta_path)
        try:
            meta = meta.with_return(self.options.get("return", 1))
        except OusterDataError as exc:
            raise FlicInputError(path, f"{exc} (metadata {meta_path.name})") from None
        index = index_udp(path)
        if index.size.size == 0:
            raise FlicInputError(
                path, f"holds no UDP packets ({index.n_records} records): no lidar data"
            )
        on_port = (
            index.port == meta.udp_port_lidar
            if meta.udp_port_lidar is not None
            else np.ones(index.size.size, dtype=bool)
        )
        lidar = np.flatnonzero(on_port & (index.size == meta.packet_size))
        if lidar.size == 0:
            sizes = ", ".join(
                f"{n} x {s} bytes on port {p}"
                for (p, s), n in _counts(index.port, index.size).items()
            )
            big = on_port & (index.size > 1000)
            if big.any():  # lidar-sized packets of another layout
                try:
                    check_packet(bytes(int(index.size[np.flatnonzero(big)[0]])), meta)
                except OusterDataError as exc:
                    raise FlicInputError(path, f"{exc} (metadata {meta_path.name})") from None
            raise FlicInputError(
                path,
                f"holds no Ouster lidar packets of {meta.packet_size} bytes (profile "
                f"{meta.profile}, {meta.beams} beams, metadata {meta_path.name}); it has {sizes}",
            )
        packets, points, partial = [], [], []
        start = 0
        max_mid = -1
        frames = decode_frames(iter_payloads(index, lidar), meta)  # one frame in memory at once
        while True:
            try:
                f = next(frames)
            except StopIteration:
                break
            except OusterDataError as exc:
                raise FlicInputError(path, f"{exc} (metadata {meta_path.name})") from None
            stop = start + f.packets
            if f.columns.any():
                max_mid = max(max_mid, int(np.flatnonzero(f.columns).max()))
            if f.complete:
                packets.append(lidar[start:stop])
                points.append(f.valid)
            else:
                partial.append(
                    f"frame id {f.frame_id}: {int(f.columns.sum())} of {meta.columns} columns, "
                    f"{f.valid:,} points"
                )
            start = stop
        if not packets and max_mid + 1 < meta.columns:
            raise FlicInputError(
                path,
                f"has no complete revolution: its packets fill columns up to {max_mid} of the "
                f"{meta.columns} that {meta_path.name} declares (lidar mode {meta.lidar_mode}): "
                "the metadata does not match the recording",
            )
        model = meta.sensor_model()
        notes = model.notes + (f"metadata {meta_path.name}",)
        if "range2" in CHANNEL_FIELDS[meta.profile]:
            notes += (f"dual-return profile: return {meta.return_index} of 2 read (--return)",)
        model = SensorModel(
            model.name, model.elevation, model.azimuth_offset, model.columns,
            model.angles_from, model.beam_origin_mm, model.columns_from, notes,
        )  # fmt: skip
        return FileInfo(
            path,
            len(packets),
            model,
            np.array(points, dtype=np.int64),
            partial,
            _PcapState(index, meta, packets),
        )

    def _load(self, info: FileInfo, k: int) -> Frame:
        from flic_cli.io.pcap import read_payloads

        state: _PcapState = info.state  # type: ignore[assignment]
        payloads = read_payloads(state.index, state.packets[k])
        try:
            (frame,) = decode_frames(payloads, state.meta)
        except (OusterDataError, ValueError) as exc:
            raise FlicInputError(info.path, f"frame {k} cannot be decoded ({exc})") from None
        image, points = frame_image(frame, state.meta)
        ref = FrameRef(self.sequence_name(info.path), k, info.path, None, FORMAT, index=k)
        return Frame(ref, points, None, image)


def _counts(port: np.ndarray, size: np.ndarray) -> dict[tuple[int, int], int]:
    out: dict[tuple[int, int], int] = {}
    for p, s in zip(port.tolist(), size.tolist(), strict=True):
        out[(p, s)] = out.get((p, s), 0) + 1
    return out
