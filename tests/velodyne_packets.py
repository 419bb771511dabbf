"""Velodyne data packets written from known ranges, per Velodyne's documented layout (tests).

A data packet (all Velodyne spinning models of the HDL / VLP line, 1,206 bytes of UDP payload):
12 data blocks of 100 bytes, then a 4-byte time stamp (microseconds past the hour) and 2 factory
bytes. A block is a 2-byte flag (``0xFFEE``; the HDL-64E's lower-block lasers 32-63 ``0xFFDD``),
the block's azimuth (uint16, 0.01 degree), and 32 channels of distance (uint16, in the model's
distance resolution: 2 mm, VLP-32C 4 mm) and reflectivity (uint8). Factory bytes: return mode
(0x37 strongest) and product id (0x21 HDL-32E, 0x22 VLP-16, 0x28 VLP-32C); the HDL-64E has no
product id (its last bytes carry a cycling status instead).

Layouts by model, as the manuals give them:

- HDL-32E, VLP-32C: one firing of the 32 lasers per block, 12 firings per packet.
- HDL-64E (S2/S3, single return): a firing of the 64 lasers is two blocks with the same azimuth,
  upper (lasers 0-31) then lower (32-63): 6 firings per packet.
"""

from __future__ import annotations

import struct

import numpy as np

PACKET_SIZE = 1206
#: model -> (lasers, blocks per firing, product id or None, distance resolution in metres)
MODELS: dict[str, tuple[int, int, int | None, float]] = {
    "HDL32E": (32, 1, 0x21, 0.002),
    "VLP32C": (32, 1, 0x28, 0.004),
    "HDL64E": (64, 2, None, 0.002),
}


def write_packets(model: str, azimuth_cdeg: np.ndarray, range_m: np.ndarray) -> list[bytes]:
    """Data packets of ``F`` firings.

    Parameters
    ----------
    model : a key of :data:`MODELS`.
    azimuth_cdeg : (F,) azimuth of every firing, 0.01 degree (taken modulo 36,000).
    range_m : (F, lasers) range of every laser's return, metres (0 = no return), by laser id.

    Returns
    -------
    The packets; the last one is padded with firings of no return when ``F`` does not fill it.
    """
    lasers, blocks_per_firing, product, res = MODELS[model]
    per_packet = 12 // blocks_per_firing
    dist = np.rint(np.asarray(range_m) / res).astype(np.int64)
    if dist.max() >= 1 << 16:
        raise ValueError("a range beyond the packet's 16-bit distance")
    out = []
    for start in range(0, len(azimuth_cdeg), per_packet):
        buf = bytearray()
        for f in range(start, start + per_packet):
            az = int(azimuth_cdeg[min(f, len(azimuth_cdeg) - 1)]) % 36000
            row = dist[f] if f < len(dist) else np.zeros(lasers, dtype=np.int64)
            for b in range(blocks_per_firing):
                buf += (b"\xff\xee" if b == 0 else b"\xff\xdd") + struct.pack("<H", az)
                for d in row[32 * b : 32 * b + 32]:
                    buf += struct.pack("<HB", int(d), 100)
        stamp = 1000 * len(out)
        if product is None:  # HDL-64E: GPS time stamp, status type and value bytes
            buf += struct.pack("<IBB", stamp, 0x37, 0x00)
        else:
            buf += struct.pack("<IBB", stamp, 0x37, product)
        assert len(buf) == PACKET_SIZE
        out.append(bytes(buf))
    return out
