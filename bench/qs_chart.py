"""Reads a qs chart file (binary PLY written by qs-dissect) without third-party modules."""
import struct


def read_chart(path):
    """Returns (positions, faces): positions a list of (x, y, z), faces a list of
    ((a, b, c), patch index)."""
    data = open(path, 'rb').read()
    h = data.index(b'end_header\n') + len(b'end_header\n')
    hdr = data[:h].decode('ascii', 'replace')
    nv = int(hdr.split('element vertex ')[1].split()[0])
    nf = int(hdr.split('element face ')[1].split()[0])
    fmt = '<B3iB6diBBB' if 'list uchar double texcoord' in hdr else '<B3iB6fiBBB'
    positions = list(struct.iter_unpack('<3d', data[h:h + 24 * nv]))
    size = struct.calcsize(fmt)
    faces = [(r[1:4], r[11]) for r in struct.iter_unpack(fmt, data[h + 24 * nv:h + 24 * nv + size * nf])]
    return positions, faces
