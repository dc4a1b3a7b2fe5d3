"""Reads the blocks of a .fgm map file (include/fragg_map/map_file_format.h) for exact
comparisons in rostests: {(bx, by, bz): 2048 bytes of 512 cells (i16 hits, i16 log_odds_fx),
x fastest} and the resolution. Blocks without an observed cell are left out, so two maps are
equal cell for cell exactly when their dicts are equal. Checks the magic and the CRC; knows
nothing of the sections after the blocks."""
import array
import struct
import zlib

UNOBSERVED = -32768
BLOCK_CELLS = 512
BLOCK_EDGE = 8
EMPTY_BLOCK = struct.pack("<hh", 0, UNOBSERVED) * BLOCK_CELLS


def read_blocks(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"FRAGGMAP":
        raise ValueError(path + ": not a .fgm file")
    if struct.unpack_from("<I", data, len(data) - 4)[0] != zlib.crc32(data[:-4]) & 0xFFFFFFFF:
        raise ValueError(path + ": bad CRC")
    _, header_bytes = struct.unpack_from("<II", data, 8)
    resolution = struct.unpack_from("<d", data, 16)[0]
    flags, count = struct.unpack_from("<IQ", data, 68)
    blocks = {}
    at = header_bytes
    for _ in range(count):
        bx, by, bz, size = struct.unpack_from("<iiiI", data, at)
        at += 16
        raw = data[at:at + size]
        at += size
        if flags & 1:
            raw = zlib.decompress(raw)
        if len(raw) != 4 * BLOCK_CELLS:
            raise ValueError(path + ": block of %d bytes" % len(raw))
        if raw != EMPTY_BLOCK:
            blocks[(bx, by, bz)] = raw
    return blocks, resolution


def observed_cells(blocks):
    """Observed cells of the blocks, summed."""
    n = 0
    for raw in blocks.values():
        log_odds = array.array("h", raw)[1::2]
        n += BLOCK_CELLS - log_odds.count(UNOBSERVED)
    return n
