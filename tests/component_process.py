"""Component processes for the end-to-end tests: `yarf-component serve` or a
compiled component binary, started as a user would, on a real socket."""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
from collections.abc import Sequence
from pathlib import Path
from types import TracebackType
from typing import Self

LISTENING = "yarf-component listening on "
YARF_COMPONENT = Path(sys.executable).parent / "yarf-component"


class ComponentProcess:
    """A component process listening at ``address``; stopped at exit.

    ``command`` is the command without ``--listen``; ``listen`` a unix
    socket path (``unix:/...``) or ``127.0.0.1:0``.
    """

    def __init__(
        self, command: Sequence[str], listen: str, *, startup_timeout: float = 30.0
    ) -> None:
        self.command = list(command)
        self.listen = listen
        self.startup_timeout = startup_timeout
        self.address = ""
        self._process: subprocess.Popen[str] | None = None
        self._log: list[str] = []

    @classmethod
    def python(cls, targets: Sequence[str | Path], listen: str, *extra: str) -> ComponentProcess:
        """``yarf-component serve TARGET... --listen ADDRESS``."""
        return cls([str(YARF_COMPONENT), "serve", *map(str, targets), *extra], listen)

    def start(self) -> None:
        if self.listen.startswith("unix:"):
            # A socket file left by a killed process would block the bind.
            Path(self.listen.removeprefix("unix:")).unlink(missing_ok=True)
        self._process = subprocess.Popen(
            [*self.command, "--listen", self.listen],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        found = threading.Event()

        def read() -> None:
            assert self._process is not None and self._process.stdout is not None
            for line in self._process.stdout:
                self._log.append(line)
                if line.startswith(LISTENING) and not found.is_set():
                    self.address = line[len(LISTENING) :].strip()
                    found.set()

        threading.Thread(target=read, daemon=True).start()
        if not found.wait(self.startup_timeout):
            self.kill()
            raise RuntimeError(f"{self.command} did not start:\n{self.log}")

    @property
    def log(self) -> str:
        return "".join(self._log)

    def is_running(self) -> bool:
        return self._process is not None and self._process.poll() is None

    def wait(self, timeout: float) -> int:
        assert self._process is not None
        return self._process.wait(timeout)

    def kill(self) -> None:
        """SIGKILL: the process vanishes without a word."""
        if self.is_running():
            assert self._process is not None
            self._process.kill()
            self._process.wait(10)

    def stop(self) -> None:
        """SIGTERM, then SIGKILL if it lingers."""
        if self.is_running():
            assert self._process is not None
            self._process.send_signal(signal.SIGTERM)
            try:
                self._process.wait(10)
            except subprocess.TimeoutExpired:
                self.kill()

    def __enter__(self) -> Self:
        self.start()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.stop()
