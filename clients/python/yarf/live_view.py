"""A job's image in the tev viewer while it renders (``yarf render --display``,
``yarf watch --display``), as pbrt-v4's ``--display-server`` shows its film.

The server keeps the progressive image of a running job (GetResult answers
mid-render); Watch says when a sample pass has finished. After a pass, and
at most every UPDATE_INTERVAL seconds, the image is fetched and the tiles
that changed are sent to tev; the final image is sent when the job ends.
The viewer is a convenience: if it goes away, a warning is shown once and
the render goes on without it.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from types import TracebackType
from typing import Self

import grpc
import numpy as np
from tqdm import tqdm

from yarf.client import Client
from yarf.tev import TevError, TevViewer
from yarf.v1 import render_pb2

# Seconds between two updates of the viewer during a render (pbrt-v4's 250 ms).
UPDATE_INTERVAL = 0.25


def _warn(message: str) -> None:
    """A line on stderr that leaves a progress bar intact."""
    tqdm.write(f"yarf: {message}", file=sys.stderr)


def image_name(status: render_pb2.JobStatus) -> str:
    """The viewer's name of the job's image: its id, and its name when it has one."""
    return f"{status.job_id} {status.name}" if status.name else status.job_id


class LiveView:
    """Shows one job's image in a tev viewer: created at the first image, updated after
    sample passes, and once more at the end."""

    def __init__(self, viewer: TevViewer, *, warn: Callable[[str], None] = _warn) -> None:
        self._viewer: TevViewer | None = viewer
        self._warn = warn
        self._name = ""
        self._sent: np.ndarray | None = None
        self._samples_sent = 0
        self._last_update = -float("inf")
        self.updates = 0

    @classmethod
    def connect(cls, host: str, port: int, *, warn: Callable[[str], None] = _warn) -> LiveView:
        """A view on the tev viewer at host:port; TevError when none answers."""
        return cls(TevViewer(host, port), warn=warn)

    @property
    def connected(self) -> bool:
        return self._viewer is not None

    def progress(self, client: Client, status: render_pb2.JobStatus) -> None:
        """After a status of the job: sends its progressive image when a pass has
        finished since the last one sent and UPDATE_INTERVAL has passed."""
        if (
            self._viewer is None
            or status.state != render_pb2.RUNNING
            or status.samples_done <= self._samples_sent
            or time.monotonic() - self._last_update < UPDATE_INTERVAL
        ):
            return
        try:
            taken, pixels, _ = client.image_pixels(status.job_id)
        except (RuntimeError, grpc.RpcError):
            return  # no image yet, or none this time: the next pass brings one
        self._show(taken, pixels)

    def finish(
        self,
        client: Client,
        status: render_pb2.JobStatus,
        pixels: np.ndarray | None = None,
    ) -> None:
        """Sends the job's final image: ``pixels`` when the caller has them, else fetched."""
        if self._viewer is None:
            return
        if pixels is None:
            try:
                status, pixels, _ = client.image_pixels(status.job_id)
            except (RuntimeError, grpc.RpcError):
                return  # the job ended without an image
        self._show(status, pixels)

    def close(self) -> None:
        """Ends the connection; the image stays in the viewer."""
        if self._viewer is not None:
            self._viewer.close()
            self._viewer = None

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()

    def _show(self, status: render_pb2.JobStatus, pixels: np.ndarray) -> None:
        assert self._viewer is not None
        pixels = np.asarray(pixels, dtype=np.float32)
        try:
            if self._sent is None or self._sent.shape != pixels.shape:
                self._name = image_name(status)
                height, width = pixels.shape[:2]
                self._viewer.create_image(self._name, width, height)
                self._sent = None
            self._viewer.update_image(self._name, pixels, previous=self._sent)
        except TevError as error:
            self._warn(f"warning: {error}; the render goes on without the viewer")
            self.close()
            return
        self._sent = pixels
        self._samples_sent = status.samples_done
        self._last_update = time.monotonic()
        self.updates += 1
