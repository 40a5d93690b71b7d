"""Pieces of the small glTF files the command-line tests write: an RGB PNG, and a unit quad (positions,
uvs, two triangles) in one embedded data: buffer."""
import base64
import struct
import zlib


def write_png(path, width, height, rgb):
    """An 8-bit RGB PNG of one colour."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress((b"\x00" + bytes(rgb) * width) * height, 6)) + chunk(b"IEND", b""))


def quad_buffers():
    """The glTF "buffers", "bufferViews" and "accessors" of a unit quad: accessor 0 POSITION, 1 TEXCOORD_0,
    2 the indices."""
    data = struct.pack("<12f", 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0) + struct.pack("<8f", 0, 0, 1, 0, 1, 1, 0, 1) + \
        struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    return {
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                        {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                      {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}],
    }
