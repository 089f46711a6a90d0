"""The checks Submit makes before a job is stored: yarfd's own, asked of ``yarfd --check-requests``.

The farm's coordinator stores jobs itself, but the rules of what a job may
say (finite numbers, sound transforms, bounded text, spp and film limits,
who may name a component address) are yarfd's, defined once in C++. A
``yarfd --check-requests`` child process answers each request with a
``SubmitCheck``: the request as its job would run, or why it is refused,
and how the job may be divided (read from its classes' capabilities).
"""

from __future__ import annotations

import struct
import subprocess
import threading
from pathlib import Path
from typing import IO

from yarf.server import find_yarfd
from yarf.v1 import render_pb2

_LENGTH = struct.Struct("<I")


class InvalidRequest(ValueError):
    """A SubmitRequest the farm refuses (INVALID_ARGUMENT), naming the offending part."""


class AddressNotAllowed(PermissionError):
    """A SubmitRequest naming a component process by address from a caller who is no admin."""


class SubmitChecker:
    """Checks SubmitRequests as yarfd's Submit does, through one ``yarfd --check-requests``.

    The child starts at the first check and again if it dies; ``close`` ends it.
    Safe to call from several threads (one check at a time).
    """

    def __init__(self, yarfd: Path | None = None) -> None:
        self._yarfd = yarfd
        self._lock = threading.Lock()
        self._process: subprocess.Popen[bytes] | None = None

    def check(self, request: render_pb2.SubmitRequest, *, admin: bool) -> render_pb2.SubmitCheck:
        """The request as its job would run (``accepted``) and how it may be divided
        (``splits``); raises InvalidRequest or AddressNotAllowed."""
        return self.check_wire(request.SerializeToString(), admin=admin)

    def check_wire(self, wire: bytes, *, admin: bool = True) -> render_pb2.SubmitCheck:
        """``check`` of a request's wire bytes, as a client may send any bytes."""
        with self._lock:
            try:
                reply = self._ask(wire)
            except (OSError, EOFError):
                # A child that died (or was killed) is started again, once.
                self._stop()
                reply = self._ask(wire)
        if reply.names_address and not admin:
            raise AddressNotAllowed(
                "naming a component process by address needs the admin role; "
                "use a class an admin registered"
            )
        if reply.error:
            raise InvalidRequest(reply.error)
        return reply

    def close(self) -> None:
        with self._lock:
            self._stop()

    def _ask(self, wire: bytes) -> render_pb2.SubmitCheck:
        process = self._running()
        assert process.stdin is not None and process.stdout is not None
        process.stdin.write(_LENGTH.pack(len(wire)) + wire)
        process.stdin.flush()
        (length,) = _LENGTH.unpack(_read_exactly(process.stdout, _LENGTH.size))
        return render_pb2.SubmitCheck.FromString(_read_exactly(process.stdout, length))

    def _running(self) -> subprocess.Popen[bytes]:
        if self._process is None or self._process.poll() is not None:
            self._process = subprocess.Popen(
                [str(self._yarfd or find_yarfd()), "--check-requests"],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
            )
        return self._process

    def _stop(self) -> None:
        if self._process is None:
            return
        process, self._process = self._process, None
        if process.stdin is not None:
            process.stdin.close()
        try:
            process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
        if process.stdout is not None:
            process.stdout.close()


def _read_exactly(stream: IO[bytes], size: int) -> bytes:
    data = b""
    while len(data) < size:
        chunk = stream.read(size - len(data))
        if not chunk:
            raise EOFError("yarfd --check-requests ended")
        data += chunk
    return data
