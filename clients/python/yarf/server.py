"""Run a yarfd on this machine for as long as a ``with`` block lasts."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import tempfile
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Self

from yarf.client import DEFAULT_TIMEOUT, Client

YARFD_ENV = "YARF_YARFD"
# Where a build of this repository puts the server: <repo>/build/bin/yarfd.
REPO_YARFD = Path(__file__).resolve().parents[3] / "build" / "bin" / "yarfd"


class ServerError(RuntimeError):
    """yarfd could not be found, did not start, or stopped unexpectedly."""


def _is_executable(path: Path) -> bool:
    return path.is_file() and os.access(path, os.X_OK)


def find_yarfd() -> Path:
    """The yarfd binary: $YARF_YARFD, else this repository's build, else yarfd on PATH."""
    from_env = os.environ.get(YARFD_ENV)
    if from_env:
        path = Path(from_env)
        if not _is_executable(path):
            raise ServerError(f"{YARFD_ENV}={from_env} is not an executable file")
        return path
    if _is_executable(REPO_YARFD):
        return REPO_YARFD
    on_path = shutil.which("yarfd")
    if on_path:
        return Path(on_path)
    raise ServerError(
        f"cannot find the yarfd binary: set {YARFD_ENV} to its path, build the repository "
        f"(expected at {REPO_YARFD}) or put yarfd on PATH"
    )


class LocalServer:
    """A yarfd child process listening on 127.0.0.1 at a free port.

    ``with LocalServer() as server: server.client().submit(...)``. The
    server writes the port it bound into a file in a private temporary
    folder; the context waits until it answers the health check with
    SERVING and stops it at exit. Its output is kept in ``log``.

    Jobs live in ``state_dir`` (yarfd's --state-dir). Without one, a
    ``state`` folder inside the private folder: every server starts with an
    empty queue and its state goes when it stops. To take a server's jobs
    over after ``stop()`` or ``kill()``, give a new server the same
    ``state_dir``, or ``start()`` this one again when it was given one.

    A server given TLS and tokens in ``extra_args`` needs ``tls_ca`` (its
    certificate) for the health check, and ``token`` for ``client()``;
    these clients never read $YARF_TOKEN or $YARF_TLS_CA.
    """

    def __init__(
        self,
        *,
        binary: str | Path | None = None,
        plugin_paths: Sequence[str | Path] = (),
        asset_root: str | Path | None = None,
        threads: int | None = None,
        extra_args: Sequence[str] = (),
        env: Mapping[str, str] | None = None,
        startup_timeout: float = 30.0,
        state_dir: str | Path | None = None,
        token: str = "",
        tls_ca: str | Path = "",
    ) -> None:
        self.binary = Path(binary) if binary is not None else find_yarfd()
        self.plugin_paths = [Path(p) for p in plugin_paths]
        self.asset_root = Path(asset_root) if asset_root is not None else None
        self.threads = threads
        self.extra_args = list(extra_args)
        self.env = dict(env) if env is not None else None
        self.startup_timeout = startup_timeout
        self.state_dir = Path(state_dir) if state_dir is not None else None
        self.token = token
        self.tls_ca = str(tls_ca)
        self._process: subprocess.Popen[bytes] | None = None
        self._folder: Path | None = None
        self._address: str | None = None
        self._log_text = ""

    @property
    def command(self) -> list[str]:
        port_file = (self._folder or Path("<folder>")) / "port"
        command = [str(self.binary), "--listen", "127.0.0.1:0", "--port-file", str(port_file)]
        command += ["--state-dir", str(self.state_path)]
        # yarfd stops with this process however it ends (a killed notebook
        # kernel leaves no server behind): on Linux, when the thread that
        # started it ends.
        command += ["--parent-pid", str(os.getpid())]
        for path in self.plugin_paths:
            command += ["--plugin-path", str(path)]
        if self.asset_root is not None:
            command += ["--asset-root", str(self.asset_root)]
        if self.threads is not None:
            command += ["--threads", str(self.threads)]
        return command + self.extra_args

    @property
    def state_path(self) -> Path:
        """The server's --state-dir: ``state_dir``, else ``state`` in the private folder."""
        if self.state_dir is not None:
            return self.state_dir
        return (self._folder or Path("<folder>")) / "state"

    @property
    def address(self) -> str:
        """ "127.0.0.1:PORT" of the running server."""
        if self._address is None:
            raise ServerError("the server is not running")
        return self._address

    @property
    def pid(self) -> int:
        if self._process is None:
            raise ServerError("the server is not running")
        return self._process.pid

    @property
    def log(self) -> str:
        """Everything the server printed (stdout and stderr) so far."""
        if self._folder is not None:
            try:
                return (self._folder / "yarfd.log").read_text(errors="replace")
            except OSError:
                pass
        return self._log_text

    def is_running(self) -> bool:
        return self._process is not None and self._process.poll() is None

    def client(self, *, timeout: float = DEFAULT_TIMEOUT) -> Client:
        """A new Client of this server (close it, or use it in a ``with``)."""
        return Client(self.address, timeout=timeout, token=self.token, tls_ca=self.tls_ca)

    def start(self) -> None:
        if self._process is not None:
            raise ServerError("the server is already started")
        self._folder = Path(tempfile.mkdtemp(prefix="yarfd-"))
        port_file = self._folder / "port"
        with open(self._folder / "yarfd.log", "wb") as log:
            self._process = subprocess.Popen(
                self.command,
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=subprocess.STDOUT,
                env=self.env,
            )
        try:
            self._address = self._wait_until_serving(port_file)
        except BaseException:
            self.stop()
            raise

    def _wait_until_serving(self, port_file: Path) -> str:
        assert self._process is not None
        deadline = time.monotonic() + self.startup_timeout
        address: str | None = None
        client: Client | None = None
        try:
            while time.monotonic() < deadline:
                code = self._process.poll()
                if code is not None:
                    raise ServerError(
                        f"{self.binary} exited with code {code} before serving:\n{self._log_tail()}"
                    )
                if address is None:
                    port = _read_port(port_file)
                    if port is not None:
                        address = f"127.0.0.1:{port}"
                        client = Client(address, token=self.token, tls_ca=self.tls_ca)
                if client is not None and client.is_serving(timeout=1.0):
                    return address  # type: ignore[return-value]
                time.sleep(0.05)
        finally:
            if client is not None:
                client.close()
        raise ServerError(
            f"{self.binary} did not serve within {self.startup_timeout:.0f} s "
            f"(port file {'read' if address else 'not written'}):\n{self._log_tail()}"
        )

    def _log_tail(self, lines: int = 40) -> str:
        return "\n".join(self.log.splitlines()[-lines:])

    def stop(self, timeout: float = 10.0) -> int | None:
        """Stops the server (SIGTERM, then SIGKILL after ``timeout``); returns its exit code."""
        return self._end(signal.SIGTERM, timeout)

    def kill(self) -> int | None:
        """Kills the server at once (SIGKILL, as a crash would); returns its exit code.

        Its jobs stay in ``state_dir`` for the next server on that folder.
        """
        return self._end(signal.SIGKILL, 10.0)

    def _end(self, how: signal.Signals, timeout: float) -> int | None:
        code: int | None = None
        if self._process is not None:
            if self._process.poll() is None:
                self._process.send_signal(how)
                try:
                    self._process.wait(timeout)
                except subprocess.TimeoutExpired:
                    self._process.kill()
                    self._process.wait()
            code = self._process.returncode
            self._process = None
        if self._folder is not None:
            self._log_text = self.log
            shutil.rmtree(self._folder, ignore_errors=True)
            self._folder = None
        self._address = None
        return code

    def __enter__(self) -> Self:
        self.start()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.stop()


def _read_port(port_file: Path) -> int | None:
    try:
        text = port_file.read_text().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() and int(text) > 0 else None
