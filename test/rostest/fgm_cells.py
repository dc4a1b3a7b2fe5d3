"""Reads the blocks of a .fgm map file (include/fragg_map/map_file_format.h) for exact
comparisons in rostests: {(bx, by, bz): 2048 bytes of 512 cells (i16 hits, i16 log_odds_fx),
x fastest} and the resolution. Blocks without an observed cell are left out, so two maps are
equal cell for cell exactly when their dicts are equal. Checks the magic and the CRC; knows
nothing of the sections after the blocks."""
import array
import struct
import subprocess
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
    version = struct.unpack_from("<I", data, 8)[0]
    flags, count = struct.unpack_from("<IQ", data, 68)
    blocks = {}
    at = header_bytes
    if version >= 5:
        read_chunks(path, data, at, count, blocks)
        return blocks, resolution
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


def unpack_chunk(codec, packed):
    if codec == 1:
        return zlib.decompress(packed)
    if codec == 2:  # zstd: the Debian zstd tool (no Python module needed)
        return subprocess.run(["zstd", "-dcq"], input=packed, stdout=subprocess.PIPE,
                              check=True).stdout
    raise ValueError("unknown block codec %d" % codec)


def read_chunks(path, data, at, count, blocks):
    """Version 5: u32 codec | u32 blocks per chunk | per chunk u32 size | packed chunk of
    n keys (3 x i32) then per block 512 hits (i16) and 512 log-odds (i16)."""
    codec, per_chunk = struct.unpack_from("<II", data, at)
    at += 8
    left = count
    while left > 0:
        n = min(per_chunk, left)
        left -= n
        size = struct.unpack_from("<I", data, at)[0]
        at += 4
        raw = unpack_chunk(codec, data[at:at + size])
        at += size
        if len(raw) != n * (12 + 4 * BLOCK_CELLS):
            raise ValueError(path + ": chunk of %d bytes" % len(raw))
        cells_at = 12 * n
        for i in range(n):
            key = struct.unpack_from("<iii", raw, 12 * i)
            planes = array.array("h", raw[cells_at + i * 4 * BLOCK_CELLS:
                                          cells_at + (i + 1) * 4 * BLOCK_CELLS])
            cells = array.array("h", [0]) * (2 * BLOCK_CELLS)
            cells[0::2] = planes[:BLOCK_CELLS]
            cells[1::2] = planes[BLOCK_CELLS:]
            block = cells.tobytes()
            if block != EMPTY_BLOCK:
                blocks[key] = block


def observed_cells(blocks):
    """Observed cells of the blocks, summed."""
    n = 0
    for raw in blocks.values():
        log_odds = array.array("h", raw)[1::2]
        n += BLOCK_CELLS - log_odds.count(UNOBSERVED)
    return n
