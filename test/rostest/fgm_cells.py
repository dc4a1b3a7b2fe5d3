"""Reads the observed cells of a .fgm map file (include/fragg_map/map_file_format.h) for
cell-for-cell comparisons in rostests: {(kx, ky, kz): (hits, log_odds_fx)} and the
resolution. Checks the magic and the CRC; knows nothing of the sections after the blocks."""
import struct
import zlib

UNOBSERVED = -32768
BLOCK_CELLS = 512


def read_cells(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"FRAGGMAP":
        raise ValueError(path + ": not a .fgm file")
    if struct.unpack_from("<I", data, len(data) - 4)[0] != zlib.crc32(data[:-4]) & 0xFFFFFFFF:
        raise ValueError(path + ": bad CRC")
    _, header_bytes = struct.unpack_from("<II", data, 8)
    resolution = struct.unpack_from("<d", data, 16)[0]
    flags, blocks = struct.unpack_from("<IQ", data, 68)
    compressed = flags & 1
    cells = {}
    at = header_bytes
    for _ in range(blocks):
        bx, by, bz, size = struct.unpack_from("<iiiI", data, at)
        at += 16
        payload = data[at:at + size]
        at += size
        raw = zlib.decompress(payload) if compressed else payload
        values = struct.unpack("<%dh" % (2 * BLOCK_CELLS), raw)
        for c in range(BLOCK_CELLS):
            log_odds = values[2 * c + 1]
            if log_odds == UNOBSERVED:
                continue
            key = ((bx << 3) | (c & 7), (by << 3) | ((c >> 3) & 7), (bz << 3) | (c >> 6))
            cells[key] = (values[2 * c], log_odds)
    return cells, resolution


def center(key, resolution):
    return tuple((k + 0.5) * resolution for k in key)
