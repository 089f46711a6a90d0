"""EXR and PNG files of a merged image, with numpy and the standard library alone.

yarfd writes its files with OpenImageIO; the coordinator has no such
dependency, so it writes the plainest valid files: an uncompressed
scanline OpenEXR of half floats and an 8-bit sRGB PNG.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np


def _srgb_bytes(linear: np.ndarray) -> np.ndarray:
    """The sRGB encoding yarfd uses, clamped to [0, 1], as 8-bit values."""
    x = np.clip(linear.astype(np.float32), 0.0, 1.0)
    encoded = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.rint(encoded * 255.0).astype(np.uint8)


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))


def encode_png(pixels: np.ndarray) -> bytes:
    """An 8-bit RGB PNG of linear float pixels [height, width, 3]."""
    height, width, _ = pixels.shape
    rows = _srgb_bytes(pixels).reshape(height, width * 3)
    # Filter type 0 (none) before every scanline.
    raw = np.hstack([np.zeros((height, 1), np.uint8), rows]).tobytes()
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + _png_chunk(b"IHDR", header)
        + _png_chunk(b"sRGB", b"\x00")
        + _png_chunk(b"IDAT", zlib.compress(raw, 6))
        + _png_chunk(b"IEND", b"")
    )


def _exr_attribute(name: str, kind: str, value: bytes) -> bytes:
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def encode_exr(pixels: np.ndarray) -> bytes:
    """A scanline OpenEXR (no compression) of half-float RGB pixels [height, width, 3]."""
    height, width, _ = pixels.shape
    channels = b"".join(
        name + b"\0" + struct.pack("<iB3xii", 1, 0, 1, 1)  # HALF, not linear, sampling 1×1
        for name in (b"B", b"G", b"R")  # channels are stored sorted by name
    )
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (
        b"\x76\x2f\x31\x01"
        + struct.pack("<i", 2)  # version 2, single-part scanline
        + _exr_attribute("channels", "chlist", channels + b"\0")
        + _exr_attribute("compression", "compression", b"\0")
        + _exr_attribute("dataWindow", "box2i", box)
        + _exr_attribute("displayWindow", "box2i", box)
        + _exr_attribute("lineOrder", "lineOrder", b"\0")
        + _exr_attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0))
        + _exr_attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
        + _exr_attribute("screenWindowWidth", "float", struct.pack("<f", 1.0))
        + b"\0"
    )
    halves = pixels.astype("<f2")
    line_bytes = width * 3 * 2
    first_line = len(header) + 8 * height
    offsets = np.arange(height, dtype="<u8") * (8 + line_bytes) + first_line
    lines = bytearray()
    for y in range(height):
        lines += struct.pack("<ii", y, line_bytes)
        # One scanline: all B values, then all G, then all R.
        lines += np.ascontiguousarray(halves[y, :, ::-1].T).tobytes()
    return header + offsets.tobytes() + bytes(lines)
