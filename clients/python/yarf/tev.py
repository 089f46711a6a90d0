"""A client of the tev image viewer's TCP protocol, to show images as they render.

tev (github.com/Tom94/tev) listens on 127.0.0.1:14158 by default; pbrt-v4's
``--display-server`` speaks the same protocol. A client only sends; tev
never answers. Every packet is

    uint32 length     the whole packet's bytes, this field included
    uint8  type       what the packet asks for
    fields            little-endian: bool as one byte, int32, int64,
                      float32; a string as UTF-8 bytes ended by a zero byte

yarf sends three of tev's packet types:

- CreateImage (4): bool grab_focus, string name, int32 width, int32 height,
  int32 channel count, then that many channel names. A new black image (one
  of the same name is replaced).
- UpdateImage, version 3 (6): bool grab_focus, string name, int32 channel
  count, the channel names, int32 x, y, width, height of a rectangle of the
  image, an int64 offset per channel, an int64 stride per channel, then
  float32 values: the value of channel c at the rectangle's pixel i (row
  major) is float number offset[c] + i * stride[c]. An interleaved RGB tile
  has offsets 0, 1, 2 and strides 3.
- CloseImage (2): string name.

tev's other packets (OpenImage 0 and 7 and ReloadImage 1, which name files
on the viewer's disk; UpdateImage versions 1 and 2, types 3 and 5; vector
graphics, 8) are not used. An update is split into tiles of TILE_SIZE
pixels, as pbrt-v4 does, so that no packet is large.
"""

from __future__ import annotations

import select
import socket
import struct
from collections.abc import Sequence
from types import TracebackType
from typing import Self

import numpy as np

DEFAULT_PORT = 14158
# Side of the square tiles an image update is sent in, pixels.
TILE_SIZE = 128
# Seconds to connect, and to hand one packet to the viewer (a viewer that
# takes longer is taken as gone).
CONNECT_TIMEOUT = 3.0
SEND_TIMEOUT = 10.0
RGB: tuple[str, ...] = ("R", "G", "B")

CLOSE_IMAGE = 2
CREATE_IMAGE = 4
UPDATE_IMAGE_V3 = 6


class TevError(OSError):
    """A viewer that cannot be reached, or that went away; the message names its address."""


def _string(text: str) -> bytes:
    encoded = text.encode("utf-8")
    if b"\0" in encoded:
        raise ValueError(f"a tev name cannot hold a zero byte: {text!r}")
    return encoded + b"\0"


def _packet(kind: int, *fields: bytes) -> bytes:
    body = bytes([kind]) + b"".join(fields)
    return struct.pack("<I", 4 + len(body)) + body


def create_image_packet(
    name: str, width: int, height: int, channels: Sequence[str], *, grab_focus: bool = True
) -> bytes:
    """CreateImage: a black ``width`` × ``height`` image of the named channels."""
    return _packet(
        CREATE_IMAGE,
        struct.pack("<?", grab_focus),
        _string(name),
        struct.pack("<iii", width, height, len(channels)),
        *(_string(channel) for channel in channels),
    )


def update_image_packet(
    name: str,
    x: int,
    y: int,
    tile: np.ndarray,
    channels: Sequence[str],
    *,
    grab_focus: bool = False,
) -> bytes:
    """UpdateImage v3: ``tile`` [height, width, channels] at pixel (x, y) of the image,
    its channels interleaved."""
    height, width, count = tile.shape
    if count != len(channels):
        raise ValueError(f"a tile of {count} channels needs {count} names, not {len(channels)}")
    values = np.ascontiguousarray(tile, dtype="<f4")
    return _packet(
        UPDATE_IMAGE_V3,
        struct.pack("<?", grab_focus),
        _string(name),
        struct.pack("<i", count),
        *(_string(channel) for channel in channels),
        struct.pack("<iiii", x, y, width, height),
        struct.pack(f"<{count}q", *range(count)),
        struct.pack(f"<{count}q", *([count] * count)),
        values.tobytes(),
    )


def close_image_packet(name: str) -> bytes:
    """CloseImage: removes the named image from the viewer."""
    return _packet(CLOSE_IMAGE, _string(name))


def tiles(height: int, width: int, size: int = TILE_SIZE) -> list[tuple[int, int, int, int]]:
    """The (x, y, width, height) tiles covering a ``width`` × ``height`` image, row by row."""
    return [
        (x, y, min(size, width - x), min(size, height - y))
        for y in range(0, height, size)
        for x in range(0, width, size)
    ]


class TevViewer:
    """A connection to a tev viewer at ``host``:``port``.

    Connecting raises TevError when no viewer answers; so does every send
    once the viewer has closed the connection or stopped reading.
    """

    def __init__(self, host: str, port: int, *, timeout: float = CONNECT_TIMEOUT) -> None:
        self.address = f"[{host}]:{port}" if ":" in host else f"{host}:{port}"
        try:
            self._socket: socket.socket | None = socket.create_connection(
                (host, port), timeout=timeout
            )
        except OSError as error:
            raise TevError(f"no tev viewer answers at {self.address} ({_reason(error)})") from None
        self._socket.settimeout(SEND_TIMEOUT)
        self._socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def create_image(
        self, name: str, width: int, height: int, channels: Sequence[str] = RGB
    ) -> None:
        """Shows a new black image (replacing one of the same name) and brings it forward."""
        self._send(create_image_packet(name, width, height, channels))

    def update_image(
        self,
        name: str,
        pixels: np.ndarray,
        channels: Sequence[str] = RGB,
        *,
        previous: np.ndarray | None = None,
    ) -> int:
        """Sends ``pixels`` [height, width, channels] as the image's values, tile by tile;
        with ``previous`` (the pixels sent before), only the tiles that changed.
        Returns how many tiles were sent."""
        height, width = pixels.shape[:2]
        sent = 0
        for x, y, w, h in tiles(height, width):
            tile = pixels[y : y + h, x : x + w]
            if previous is not None and np.array_equal(
                tile, previous[y : y + h, x : x + w], equal_nan=True
            ):
                continue
            self._send(update_image_packet(name, x, y, tile, channels))
            sent += 1
        return sent

    def close_image(self, name: str) -> None:
        self._send(close_image_packet(name))

    def close(self) -> None:
        if self._socket is not None:
            self._socket.close()
            self._socket = None

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()

    def _send(self, packet: bytes) -> None:
        if self._socket is None:
            raise TevError(f"the connection to the tev viewer at {self.address} is closed")
        try:
            if self._closed_by_viewer():
                raise TevError(f"the tev viewer at {self.address} closed the connection")
            self._socket.sendall(packet)
        except TevError:
            self.close()
            raise
        except OSError as error:
            self.close()
            raise TevError(
                f"the tev viewer at {self.address} went away ({_reason(error)})"
            ) from None

    def _closed_by_viewer(self) -> bool:
        """Whether the viewer has closed its end: tev sends nothing, so a readable
        socket with no bytes is the end of the connection. Checked before each send,
        since a send into a closed connection may succeed once."""
        assert self._socket is not None
        readable, _, _ = select.select([self._socket], [], [], 0)
        if not readable:
            return False
        return self._socket.recv(1, socket.MSG_PEEK) == b""


def _reason(error: OSError) -> str:
    if isinstance(error, TimeoutError):
        return "timed out"
    return error.strerror or str(error) or type(error).__name__
