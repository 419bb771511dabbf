"""UDP payloads of a packet capture (``.pcap`` / ``.pcapng``), read with dpkt.

The sensor readers (:mod:`flic_cli.io.ouster`, :mod:`flic_cli.io.velodyne`) decode UDP payloads;
this module finds them. :func:`index_udp` reads a capture once and returns where every UDP
payload lies in the file, so that a frame can later be read by slicing those bytes
(:func:`read_payloads`) instead of parsing the whole capture again.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flic_cli.errors import FlicInputError

#: Classic libpcap magic numbers (as the first 4 bytes of the file) with 16-byte record headers.
_CLASSIC_MAGICS = {
    b"\xd4\xc3\xb2\xa1",  # little-endian, microseconds
    b"\xa1\xb2\xc3\xd4",  # big-endian, microseconds
    b"\x4d\x3c\xb2\xa1",  # little-endian, nanoseconds
    b"\xa1\xb2\x3c\x4d",  # big-endian, nanoseconds
}
_PCAPNG_MAGIC = b"\x0a\x0d\x0d\x0a"
PCAP_SUFFIXES = (".pcap", ".pcapng", ".cap")


@dataclass(frozen=True, eq=False)
class UdpIndex:
    """Where a capture's UDP payloads lie.

    Attributes
    ----------
    path : the capture.
    port : (P,) int32 destination port of every UDP packet, in capture order.
    size : (P,) int64 payload length in bytes.
    offset : (P,) int64 byte offset of the payload in the file, or None for a pcapng capture
        (whose payloads are read by parsing the file again).
    time : (P,) float64 capture time stamp in seconds.
    n_records : number of records in the capture (UDP or not).
    """

    path: Path
    port: np.ndarray
    size: np.ndarray
    offset: np.ndarray | None
    time: np.ndarray
    n_records: int


def is_capture(path: Path) -> bool:
    """True when ``path`` is a file that starts like a pcap or pcapng capture."""
    if not path.is_file():
        return False
    try:
        with open(path, "rb") as f:
            head = f.read(4)
    except OSError:
        return False
    return head in _CLASSIC_MAGICS or head == _PCAPNG_MAGIC


def _reader(path: Path, f):  # noqa: ANN001, ANN202 (dpkt has no type hints)
    import dpkt

    head = f.read(4)
    f.seek(0)
    try:
        if head == _PCAPNG_MAGIC:
            return dpkt.pcapng.Reader(f), False
        if head in _CLASSIC_MAGICS:
            return dpkt.pcap.Reader(f), True
    except (ValueError, dpkt.UnpackError) as exc:
        raise FlicInputError(path, f"is not a readable capture ({exc})") from None
    raise FlicInputError(path, "is not a pcap or pcapng capture (unknown magic number)")


def _record_header(f):  # noqa: ANN001, ANN202
    """dpkt's record header class for a classic pcap file (by its magic number)."""
    import dpkt

    f.seek(0)
    magic = dpkt.pcap.FileHdr(f.read(24)).magic
    return dpkt.pcap.MAGIC_TO_PKT_HDR[magic]


def _udp_payload(buf: bytes, linktype: int) -> tuple[int, bytes] | None:
    """``(destination port, payload)`` of a captured frame, None unless it is IPv4/IPv6 UDP."""
    import dpkt

    try:
        if linktype == dpkt.pcap.DLT_EN10MB:
            ip = dpkt.ethernet.Ethernet(buf).data
        elif linktype in (dpkt.pcap.DLT_RAW, 101, 228, 229):  # raw IP (LINKTYPE_RAW, IPV4, IPV6)
            ip = dpkt.ip.IP(buf) if buf[:1] and buf[0] >> 4 == 4 else dpkt.ip6.IP6(buf)
        elif linktype == dpkt.pcap.DLT_LINUX_SLL:
            ip = dpkt.sll.SLL(buf).data
        else:
            return None
    except (dpkt.UnpackError, IndexError, ValueError):
        return None
    if not isinstance(ip, (dpkt.ip.IP, dpkt.ip6.IP6)):
        return None
    if isinstance(ip, dpkt.ip.IP) and (ip.mf or ip.offset):
        return None  # an IP fragment: not a whole UDP datagram
    udp = ip.data
    if not isinstance(udp, dpkt.udp.UDP):
        return None
    return int(udp.dport), bytes(udp.data)


def _records(path: Path) -> Iterator[tuple[float, bytes, int, int]]:
    """``(time, frame bytes, file offset of the frame or -1, linktype)`` of every record.

    Raises
    ------
    FlicInputError
        When the file is no capture or its last record is cut short (a truncated capture).
    """
    import dpkt

    try:
        f = open(path, "rb")  # noqa: SIM115 (closed in finally)
    except OSError as exc:
        raise FlicInputError(path, f"cannot be read ({exc.strerror or exc})") from None
    try:
        reader, classic = _reader(path, f)
        linktype = reader.datalink()
        pos = 24  # classic pcap: global header, then 16-byte record headers
        caplens: list[int] = []
        try:
            for ts, buf in reader:
                if classic:
                    yield float(ts), buf, pos + 16, linktype
                    pos += 16 + len(buf)
                else:
                    yield float(ts), buf, -1, linktype
                caplens.append(len(buf))
        except (dpkt.NeedData, dpkt.UnpackError, ValueError) as exc:
            raise FlicInputError(
                path, f"is truncated or damaged after record {len(caplens)} ({exc})"
            ) from None
        if classic and caplens:
            # dpkt returns a cut-off last record as it is: compare with its header's length
            header_cls = _record_header(f)
            f.seek(pos - 16 - caplens[-1])
            hdr = header_cls(f.read(16))
            if hdr.caplen != caplens[-1]:
                raise FlicInputError(
                    path,
                    f"is truncated: its last record (number {len(caplens)}) holds "
                    f"{caplens[-1]} of its {hdr.caplen} bytes",
                )
    finally:
        f.close()


def index_udp(path: str | Path) -> UdpIndex:
    """Read a capture once: the destination port, size and file offset of every UDP payload.

    Raises
    ------
    FlicInputError
        When the file cannot be read, is no pcap/pcapng capture, or is truncated.
    """
    path = Path(path)
    ports: list[int] = []
    sizes: list[int] = []
    offsets: list[int] = []
    times: list[float] = []
    n = 0
    classic = True
    for ts, buf, pos, linktype in _records(path):
        n += 1
        udp = _udp_payload(buf, linktype)
        if udp is None:
            continue
        port, payload = udp
        ports.append(port)
        sizes.append(len(payload))
        times.append(ts)
        if pos < 0:
            classic = False
            continue
        start = len(buf) - len(payload)
        if buf[start:] != payload:  # trailing link-layer padding
            start = buf.rfind(payload)
        offsets.append(pos + start)
    return UdpIndex(
        path,
        np.array(ports, dtype=np.int32),
        np.array(sizes, dtype=np.int64),
        np.array(offsets, dtype=np.int64) if classic else None,
        np.array(times, dtype=np.float64),
        n,
    )


def read_payloads(index: UdpIndex, which: np.ndarray) -> list[bytes]:
    """The UDP payloads number ``which`` (indices into ``index``), in that order.

    A classic pcap is read by slicing one span of the file; a pcapng capture is parsed again.
    """
    which = np.asarray(which, dtype=np.int64)
    if which.size == 0:
        return []
    if index.offset is not None:
        off = index.offset[which]
        size = index.size[which]
        start = int(off.min())
        end = int((off + size).max())
        with open(index.path, "rb") as f:
            f.seek(start)
            span = f.read(end - start)
        if len(span) != end - start:
            raise FlicInputError(index.path, "changed since it was opened (shorter now)")
        rel = (off - start).tolist()
        return [span[o : o + s] for o, s in zip(rel, size.tolist(), strict=True)]
    wanted = {int(k): i for i, k in enumerate(which)}
    out: list[bytes] = [b""] * which.size
    k = 0
    for _, buf, _, linktype in _records(index.path):
        udp = _udp_payload(buf, linktype)
        if udp is None:
            continue
        if k in wanted:
            out[wanted[k]] = udp[1]
        k += 1
    return out


def iter_payloads(index: UdpIndex, which: np.ndarray, chunk: int = 2048) -> Iterator[bytes]:
    """The payloads number ``which``, in that order, read ``chunk`` at a time (so that a long
    capture is never held in memory at once)."""
    which = np.asarray(which, dtype=np.int64)
    for start in range(0, which.size, chunk):
        yield from read_payloads(index, which[start : start + chunk])
