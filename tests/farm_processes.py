"""A render farm on loopback for tests and benchmarks: a real nats-server with
JetStream, coordinators and nodes as child processes (``python -m yarf.farm``).

Every process writes its output to a log file in the farm's folder; logs
are kept in memory when the process stops so that a failing test can show them.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import TracebackType
from typing import Any, Self, TypeVar

import pytest

from yarf import Client

NATS_BINARIES = ("/usr/sbin/nats-server", "/usr/bin/nats-server")
START_TIMEOUT = 60.0
T = TypeVar("T")


def find_nats_server() -> str:
    found = shutil.which("nats-server")
    for candidate in (found, *NATS_BINARIES):
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    raise FileNotFoundError("nats-server is not installed (apt-get install nats-server)")


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def _wait_for(condition: Callable[[], T | None], what: str, timeout: float = START_TIMEOUT) -> T:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.05)
    raise TimeoutError(f"{what} within {timeout:.0f} s")


class FarmProcess:
    """A child process whose output goes to ``log_path``."""

    def __init__(self, command: Sequence[str], log_path: Path) -> None:
        self.command = list(command)
        self.log_path = log_path
        with open(log_path, "ab") as log:
            self.process = subprocess.Popen(
                self.command, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT
            )

    @property
    def pid(self) -> int:
        return self.process.pid

    @property
    def log(self) -> str:
        try:
            return self.log_path.read_text(errors="replace")
        except OSError:
            return ""

    def is_running(self) -> bool:
        return self.process.poll() is None

    def check_running(self, what: str) -> None:
        if not self.is_running():
            raise RuntimeError(
                f"{what} exited with code {self.process.returncode}:\n{self.log[-3000:]}"
            )

    def kill(self) -> None:
        """SIGKILL: the process gets no chance to tidy up."""
        if self.is_running():
            self.process.kill()
        self.process.wait()

    def stop(self, timeout: float = 10.0) -> None:
        if self.is_running():
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


class NatsServer(FarmProcess):
    """nats-server -js on 127.0.0.1 at a free port, its store in ``folder``."""

    def __init__(self, folder: Path) -> None:
        self.port = free_port()
        self.url = f"nats://127.0.0.1:{self.port}"
        store = folder / "jetstream"
        super().__init__(
            [find_nats_server(), "-js", "-sd", str(store), "-a", "127.0.0.1", "-p", str(self.port)],
            folder / "nats.log",
        )
        _wait_for(self._accepts, f"nats-server did not listen on {self.port}")

    def _accepts(self) -> bool:
        self.check_running("nats-server")
        try:
            with socket.create_connection(("127.0.0.1", self.port), timeout=0.5):
                return True
        except OSError:
            return False


class Coordinator(FarmProcess):
    """``yarf-farm coordinator`` at a free port; ``address`` once it serves.

    A coordinator given TLS in ``extra_args`` needs ``tls_ca`` (its
    certificate) for the health check and its clients.
    """

    def __init__(
        self,
        nats_url: str,
        state_dir: Path,
        log_path: Path,
        extra_args: Sequence[str] = (),
        tls_ca: Path | None = None,
    ) -> None:
        self.tls_ca = tls_ca
        port_file = state_dir.parent / f"{state_dir.name}.port"
        port_file.unlink(missing_ok=True)
        super().__init__(
            [
                sys.executable,
                "-m",
                "yarf.farm",
                "coordinator",
                "--nats",
                nats_url,
                "--listen",
                "127.0.0.1:0",
                "--state-dir",
                str(state_dir),
                "--port-file",
                str(port_file),
                *extra_args,
            ],
            log_path,
        )

        def serving() -> str | None:
            self.check_running("the coordinator")
            try:
                port = int(port_file.read_text().strip())
            except (OSError, ValueError):
                return None
            # The health check needs no token.
            ca = str(self.tls_ca or "")
            with Client(f"127.0.0.1:{port}", token="", tls_ca=ca) as client:
                return f"127.0.0.1:{port}" if client.is_serving(timeout=1.0) else None

        self.address: str = _wait_for(serving, "the coordinator did not serve")

    def client(self, timeout: float = 60.0, token: str | None = None) -> Client:
        """A client; ``token`` None: $YARF_TOKEN, as any client."""
        return Client(self.address, timeout=timeout, token=token, tls_ca=self.tls_ca)


class Node(FarmProcess):
    """``yarf-farm node`` with its own yarfd (``threads`` render threads), or
    on the yarfd at ``yarfd`` with ``yarfd_args`` (``--token``, ``--ca``);
    ``extra_args`` go to the node (``--task-timeout``)."""

    def __init__(
        self,
        nats_url: str,
        name: str,
        log_path: Path,
        cache_dir: Path,
        threads: int = 1,
        yarfd: str | None = None,
        yarfd_args: Sequence[str] = (),
        extra_args: Sequence[str] = (),
    ) -> None:
        self.name = name
        target = ["--threads", str(threads)] if yarfd is None else ["--yarfd", yarfd, *yarfd_args]
        super().__init__(
            [
                sys.executable,
                "-m",
                "yarf.farm",
                "node",
                "--nats",
                nats_url,
                *target,
                "--name",
                name,
                "--cache-dir",
                str(cache_dir),
                *extra_args,
            ],
            log_path,
        )

        def ready() -> bool:
            self.check_running(f"node {name}")
            return "node ready" in self.log

        _wait_for(ready, f"node {name} was not ready")
        # The node's own yarfd, which stops with it; None: someone else's.
        self.yarfd_pid: int | None = None
        if yarfd is None:
            self.yarfd_pid = int(self.events("yarfd started")[0]["pid"])

    def events(self, kind: str) -> list[dict[str, Any]]:
        """The node's ``<kind> {json}`` log lines, oldest first."""
        pattern = re.compile(re.escape(kind) + r" (\{.*\})$")
        return [
            json.loads(match.group(1))
            for line in self.log.splitlines()
            if (match := pattern.search(line))
        ]

    def kill(self) -> None:
        """SIGKILL of the node and of its yarfd, as when the machine dies."""
        super().kill()
        self._kill_yarfd()

    def stop(self, timeout: float = 10.0) -> None:
        super().stop(timeout)
        if self.process.returncode != 0:
            self._kill_yarfd()  # the node had no chance to stop it

    def _kill_yarfd(self) -> None:
        if self.yarfd_pid is None:
            return
        try:
            command = Path(f"/proc/{self.yarfd_pid}/cmdline").read_bytes()
        except OSError:
            return  # gone
        if b"yarfd" in command:  # not a process that took the number since
            os.kill(self.yarfd_pid, signal.SIGKILL)


class Farm:
    """A nats-server, and the coordinators and nodes a test starts on it; all stop at exit."""

    def __init__(self, *, coordinator_args: Sequence[str] = (), tls_ca: Path | None = None) -> None:
        self.folder = Path(tempfile.mkdtemp(prefix="yarf-farm-"))
        self.coordinator_args = list(coordinator_args)
        self.tls_ca = tls_ca
        self.state_dir = self.folder / "state"
        self.nats: NatsServer | None = None
        self.coordinator: Coordinator | None = None
        self.nodes: list[Node] = []
        self._coordinators = 0
        self.logs: dict[str, str] = {}

    def __enter__(self) -> Self:
        self.nats = NatsServer(self.folder)
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()

    @property
    def nats_url(self) -> str:
        assert self.nats is not None
        return self.nats.url

    def start_coordinator(self) -> Coordinator:
        """A coordinator on the farm's state folder (again after a kill: the same folder)."""
        self._coordinators += 1
        log_path = self.folder / f"coordinator-{self._coordinators}.log"
        self.coordinator = Coordinator(
            self.nats_url, self.state_dir, log_path, self.coordinator_args, self.tls_ca
        )
        return self.coordinator

    def start_node(
        self,
        threads: int = 1,
        yarfd: str | None = None,
        yarfd_args: Sequence[str] = (),
        extra_args: Sequence[str] = (),
    ) -> Node:
        """A node with its own yarfd, or on ``yarfd`` (see Node)."""
        name = f"node-{len(self.nodes) + 1}"
        log_path, cache = self.folder / f"{name}.log", self.folder / "scene-cache"
        node = Node(self.nats_url, name, log_path, cache, threads, yarfd, yarfd_args, extra_args)
        self.nodes.append(node)
        return node

    def client(self, timeout: float = 60.0, token: str | None = None) -> Client:
        assert self.coordinator is not None
        return self.coordinator.client(timeout, token)

    def log_tail(self, lines: int = 25) -> str:
        """The end of every process's log, for a failing test's report."""
        parts = []
        for path in sorted(self.folder.glob("*.log")):
            text = path.read_text(errors="replace").splitlines()[-lines:]
            parts.append(f"--- {path.name}\n" + "\n".join(text))
        return "\n".join(parts)

    def close(self) -> None:
        for node in self.nodes:
            node.stop()
        if self.coordinator is not None:
            self.coordinator.stop()
        if self.nats is not None:
            self.nats.stop()
        for path in self.folder.glob("*.log"):
            self.logs[path.name] = path.read_text(errors="replace")
        shutil.rmtree(self.folder, ignore_errors=True)


@contextmanager
def two_node_farm(session: pytest.Session, coordinator_args: Sequence[str]) -> Iterator[Farm]:
    """A coordinator and two nodes for a module's tests; their logs are printed at the
    end when a test of ``session`` (pytest's) failed meanwhile."""
    failed_before = session.testsfailed
    with Farm(coordinator_args=coordinator_args) as running:
        running.start_coordinator()
        running.start_node()
        running.start_node()
        yield running
        if session.testsfailed > failed_before:
            print(running.log_tail())
