"""The live view: ``yarf render --display`` and ``yarf watch --display`` stream the
progressive image to a tev viewer, here a small listener that reads tev's protocol.

The listener parses packets as tev's documentation of its protocol states
them (a little-endian uint32 length that counts itself, a type byte, then
the fields), written apart from the client's encoder so that the two check
each other.
"""

from __future__ import annotations

import socket
import struct
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from conftest import CORNELL_BOX

from yarf import Client, LocalServer, live_view, load_scene
from yarf.cli import main
from yarf.v1 import render_pb2

# A film that is not square, over one 128-pixel tile in each direction and not a multiple.
WIDTH, HEIGHT = 136, 132
# Enough samples for a render of about a second, so that it has several updates.
SPP = "16"
Yarf = Callable[..., tuple[int, str, str]]


@dataclass
class Received:
    """What the viewer was sent, as it understood it."""

    created: list[tuple[str, int, int, list[str]]] = field(default_factory=list)
    # Each update packet: the image's name, x, y, and the tile [h, w, channels].
    tiles: list[tuple[str, int, int, np.ndarray]] = field(default_factory=list)
    # The image after each update packet (copies), by name.
    images: dict[str, np.ndarray] = field(default_factory=dict)
    snapshots: list[np.ndarray] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)


class _Reader:
    """The fields of one packet's body, read in order."""

    def __init__(self, body: bytes) -> None:
        self.body = body
        self.at = 0

    def take(self, size: int) -> bytes:
        if self.at + size > len(self.body):
            raise ValueError(f"the packet ends at {len(self.body)}, a field wants {self.at + size}")
        chunk = self.body[self.at : self.at + size]
        self.at += size
        return chunk

    def unpack(self, layout: str) -> tuple[int, ...]:
        return struct.unpack("<" + layout, self.take(struct.calcsize("<" + layout)))

    def text(self) -> str:
        end = self.body.index(b"\0", self.at)
        value = self.body[self.at : end].decode("utf-8")
        self.at = end + 1
        return value


class TevListener:
    """A tev stand-in on 127.0.0.1: accepts one connection and records its packets
    (CreateImage, UpdateImage v3); ``close_after`` update packets it hangs up."""

    def __init__(self, *, close_after: int | None = None) -> None:
        self.received = Received()
        self.close_after = close_after
        self.hung_up = threading.Event()
        self._server = socket.create_server(("127.0.0.1", 0))
        self.address = f"127.0.0.1:{self._server.getsockname()[1]}"
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        self._server.settimeout(60)
        try:
            connection, _ = self._server.accept()
        except OSError:
            return
        with connection:
            try:
                while self.close_after is None or len(self.received.tiles) < self.close_after:
                    header = self._read(connection, 4)
                    if header is None:
                        return
                    (length,) = struct.unpack("<I", header)
                    body = self._read(connection, length - 4)
                    if body is None:
                        self.received.errors.append("the connection ended inside a packet")
                        return
                    self._parse(body)
            except (ValueError, OSError) as error:
                self.received.errors.append(f"{type(error).__name__}: {error}")
        self.hung_up.set()

    @staticmethod
    def _read(connection: socket.socket, size: int) -> bytes | None:
        data = b""
        while len(data) < size:
            chunk = connection.recv(size - len(data))
            if not chunk:
                return None
            data += chunk
        return data

    def _parse(self, body: bytes) -> None:
        reader = _Reader(body)
        (kind,) = reader.unpack("B")
        received = self.received
        if kind == 4:  # CreateImage
            reader.unpack("?")
            name = reader.text()
            width, height, count = reader.unpack("iii")
            channels = [reader.text() for _ in range(count)]
            received.created.append((name, width, height, channels))
            received.images[name] = np.zeros((height, width, count), np.float32)
        elif kind == 6:  # UpdateImage, version 3
            reader.unpack("?")
            name = reader.text()
            (count,) = reader.unpack("i")
            channels = [reader.text() for _ in range(count)]
            x, y, width, height = reader.unpack("iiii")
            offsets = reader.unpack(f"{count}q")
            strides = reader.unpack(f"{count}q")
            floats = np.frombuffer(reader.take(len(body) - reader.at), dtype="<f4")
            pixel = np.arange(width * height)
            tile = np.stack(
                [floats[offsets[c] + pixel * strides[c]] for c in range(count)], axis=-1
            ).reshape(height, width, count)
            image = received.images[name]  # an update of an image never created fails
            assert channels == ["R", "G", "B"][:count], channels
            image[y : y + height, x : x + width] = tile
            received.tiles.append((name, x, y, tile))
            received.snapshots.append(image.copy())
        else:
            raise ValueError(f"packet type {kind} was not expected")

    def finish(self) -> Received:
        """What was received, once the client has gone (its connection ended)."""
        self._thread.join(timeout=30)
        self._server.close()
        assert not self._thread.is_alive(), "the viewer's connection did not end"
        return self.received


@pytest.fixture
def viewer() -> Iterator[TevListener]:
    listener = TevListener()
    yield listener
    listener._server.close()


@pytest.fixture
def yarf(server: LocalServer, capsys: pytest.CaptureFixture[str]) -> Yarf:
    """Runs ``yarf ARGS... --server ADDRESS`` in process; returns the exit code, stdout, stderr."""

    def run(*args: str) -> tuple[int, str, str]:
        capsys.readouterr()
        try:
            code = main([*args, "--server", server.address])
        except SystemExit as exit:
            code = int(exit.code or 0)
        out, err = capsys.readouterr()
        return code, out, err

    return run


@pytest.fixture(autouse=True)
def frequent_updates(monkeypatch: pytest.MonkeyPatch) -> None:
    """An update after every sample pass, so that a short render on a fast machine has
    several."""
    monkeypatch.setattr(live_view, "UPDATE_INTERVAL", 0.0)


def free_address() -> str:
    """An address of this machine where nothing listens."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return f"127.0.0.1:{probe.getsockname()[1]}"


def render_args(output: Path, *extra: str) -> list[str]:
    return [
        "render", str(CORNELL_BOX), "-o", str(output), "--res", f"{WIDTH}x{HEIGHT}",
        "--spp", SPP, "-q", *extra,
    ]  # fmt: skip


def job_id_of(out: str) -> str:
    return out.rsplit("job ", 1)[1].rstrip(")\n")


def test_render_streams_progressive_updates_and_ends_with_the_fetched_image(
    yarf: Yarf, client: Client, viewer: TevListener, tmp_path: Path
) -> None:
    code, out, err = yarf(*render_args(tmp_path / "out.exr", "--display", viewer.address))
    assert code == 0, err
    received = viewer.finish()
    assert not received.errors, received.errors
    job_id = job_id_of(out)

    assert len(received.created) == 1, "the image is created once"
    name, width, height, channels = received.created[0]
    assert job_id in name and "scene.json" in name
    assert (width, height, channels) == (WIDTH, HEIGHT, ["R", "G", "B"])
    assert {tile_name for tile_name, *_ in received.tiles} == {name}

    # The film is sent in tiles of 128 pixels, those at the right and bottom edges narrower.
    expected_tiles = {
        (x, y, (min(128, HEIGHT - y), min(128, WIDTH - x), 3)) for x in (0, 128) for y in (0, 128)
    }
    assert {(x, y, tile.shape) for _, x, y, tile in received.tiles} == expected_tiles

    final = client.image(job_id)
    assert np.array_equal(received.images[name], final), "the viewer's last image is the result"
    # Updates came during the render: the first tile several times with fewer samples.
    progressive = [
        tile
        for _, x, _, tile in received.tiles
        if x == 0 and not np.array_equal(tile, final[:, :128])
    ]
    assert len(progressive) > 1, f"{len(received.tiles)} tiles, {len(progressive)} progressive"
    assert client.status(job_id).state == render_pb2.SUCCEEDED


def test_watch_shows_a_submitted_job_to_its_end(
    yarf: Yarf, client: Client, viewer: TevListener
) -> None:
    scene = load_scene(CORNELL_BOX)
    scene.film.width, scene.film.height = WIDTH, HEIGHT
    job_id = client.submit(scene, spp=int(SPP), seed=2, name="watched")
    code, out, err = yarf("watch", job_id, "-q", "--display", viewer.address)
    assert code == 0, err
    assert "SUCCEEDED" in out
    received = viewer.finish()
    assert not received.errors, received.errors
    assert [(w, h, c) for _, w, h, c in received.created] == [(WIDTH, HEIGHT, ["R", "G", "B"])]
    name = received.created[0][0]
    assert name == f"{job_id} watched"
    assert np.array_equal(received.images[name], client.image(job_id))


def test_an_unreachable_viewer_is_one_line_and_exit_2_before_anything_renders(
    yarf: Yarf, client: Client, tmp_path: Path
) -> None:
    address = free_address()
    jobs_before = len(client.list())
    started = time.monotonic()
    code, _, err = yarf(*render_args(tmp_path / "out.exr", "--display", address))
    assert code == 2, err
    assert f"--display: no tev viewer answers at {address}" in err, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert time.monotonic() - started < 10
    assert len(client.list()) == jobs_before, "a job was submitted"
    assert not list(tmp_path.glob("out.*"))

    code, _, err = yarf("watch", "job-000001", "--display", address)
    assert code == 2 and f"no tev viewer answers at {address}" in err, err


@pytest.mark.parametrize("display", ["14158", "localhost", "host:port", ":14158", "h:70000"])
def test_a_bad_display_address_is_one_line_and_exit_2(
    yarf: Yarf, client: Client, tmp_path: Path, display: str
) -> None:
    jobs_before = len(client.list())
    code, _, err = yarf(*render_args(tmp_path / "out.exr", "--display", display))
    assert code == 2, err
    assert "--display: expected HOST:PORT of a tev viewer" in err, err
    assert len(err.strip().splitlines()) == 1, err
    assert len(client.list()) == jobs_before


def test_a_viewer_that_goes_away_mid_render_leaves_the_render_finishing_with_a_warning(
    yarf: Yarf, client: Client, tmp_path: Path
) -> None:
    viewer = TevListener(close_after=1)
    output = tmp_path / "out.exr"
    code, out, err = yarf(*render_args(output, "--display", viewer.address))
    assert code == 0, err
    received = viewer.finish()
    assert viewer.hung_up.is_set() and len(received.tiles) == 1
    warnings = [line for line in err.splitlines() if "warning:" in line]
    assert len(warnings) == 1, err
    assert f"the tev viewer at {viewer.address}" in warnings[0]
    assert "the render goes on without the viewer" in warnings[0]
    assert "Traceback" not in err
    assert output.is_file() and "wrote" in out
    assert client.status(job_id_of(out)).state == render_pb2.SUCCEEDED
