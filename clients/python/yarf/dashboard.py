"""``yarf dashboard``: a web page of a yarfd's queue and the JSON API behind it.

The page's files (index.html, app.js, style.css) live in clients/web; this
module serves them and turns a few HTTP requests into RenderService calls:

- ``GET /api/jobs``: ``{"jobs": [job, ...]}``, newest first
- ``GET /api/jobs/<id>/preview.png``: the job's image so far, as PNG
- ``POST /api/jobs/<id>/cancel``: the job's status after the request
- ``POST /api/jobs/<id>/priority`` with ``{"priority": P}``: the job's new status

A failed call answers ``{"error": message, "code": grpc code}`` with the
HTTP status that matches the gRPC code (NOT_FOUND → 404...).
"""

from __future__ import annotations

import json
import re
import socket
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, TypeVar
from urllib.parse import unquote, urlsplit

import grpc

from yarf.client import FINAL_STATES, Client
from yarf.v1 import render_pb2

DEFAULT_LISTEN = "127.0.0.1:8080"
# Where the page's files are in the repository (the package is installed editable).
WEB_DIR = Path(__file__).resolve().parents[2] / "web"
CONTENT_TYPES = {
    ".html": "text/html; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".css": "text/css; charset=utf-8",
    ".svg": "image/svg+xml",
    ".png": "image/png",
}
# The page loads nothing from elsewhere and runs no inline script.
SECURITY_HEADERS = {
    "Content-Security-Policy": "default-src 'self'; img-src 'self'; frame-ancestors 'none'",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
}
HTTP_STATUS_OF_GRPC = {
    grpc.StatusCode.INVALID_ARGUMENT: HTTPStatus.BAD_REQUEST,
    grpc.StatusCode.OUT_OF_RANGE: HTTPStatus.BAD_REQUEST,
    grpc.StatusCode.UNAUTHENTICATED: HTTPStatus.UNAUTHORIZED,
    grpc.StatusCode.PERMISSION_DENIED: HTTPStatus.FORBIDDEN,
    grpc.StatusCode.NOT_FOUND: HTTPStatus.NOT_FOUND,
    grpc.StatusCode.FAILED_PRECONDITION: HTTPStatus.CONFLICT,
    grpc.StatusCode.ALREADY_EXISTS: HTTPStatus.CONFLICT,
    grpc.StatusCode.RESOURCE_EXHAUSTED: HTTPStatus.TOO_MANY_REQUESTS,
    grpc.StatusCode.UNIMPLEMENTED: HTTPStatus.NOT_IMPLEMENTED,
    grpc.StatusCode.UNAVAILABLE: HTTPStatus.SERVICE_UNAVAILABLE,
    grpc.StatusCode.DEADLINE_EXCEEDED: HTTPStatus.GATEWAY_TIMEOUT,
}
PREVIEW_PATH = re.compile(r"/api/jobs/([^/]+)/preview\.png")
ACTION_PATH = re.compile(r"/api/jobs/([^/]+)/(cancel|priority)")
MAX_BODY_BYTES = 4096

_T = TypeVar("_T")


class DashboardError(Exception):
    """A request the dashboard refuses, with the HTTP status to answer."""

    def __init__(self, status: HTTPStatus, message: str, code: str = "") -> None:
        super().__init__(message)
        self.status = status
        self.code = code


def find_web_dir(web_dir: Path | None = None) -> Path:
    """The folder of the page's files: ``web_dir``, else the repository's clients/web."""
    folder = web_dir or WEB_DIR
    if not (folder / "index.html").is_file():
        raise FileNotFoundError(
            f"the dashboard's page is not at {folder} (no index.html): it ships in the yarf "
            "repository's clients/web; install the client from there (pip install -e "
            "clients/python) or pass --web-dir"
        )
    return folder


def parse_listen(listen: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:PORT`` for IPv6) as a host and a port."""
    host, colon, port = listen.rpartition(":")
    if not colon or not host or not port.isdigit() or int(port) > 65535:
        raise ValueError(f"--listen needs HOST:PORT, got {listen!r}")
    return host.strip("[]"), int(port)


def job_json(status: render_pb2.JobStatus) -> dict[str, Any]:
    """What the page shows of a job."""
    return {
        "job_id": status.job_id,
        "name": status.name,
        "owner": status.owner,
        "state": render_pb2.JobState.Name(status.state),
        "priority": status.priority,
        "samples_done": status.samples_done,
        "samples_total": status.samples_total,
        "percent": status.percent,
        "elapsed_seconds": status.elapsed_seconds,
        "eta_seconds": status.eta_seconds,
        "error": status.error,
        "attempts": status.attempts,
        "submitted_at": status.submitted_at,
    }


def _grpc_error(error: grpc.RpcError) -> DashboardError:
    if not isinstance(error, grpc.Call):
        return DashboardError(HTTPStatus.BAD_GATEWAY, str(error))
    code = error.code()
    status = HTTP_STATUS_OF_GRPC.get(code, HTTPStatus.BAD_GATEWAY)
    return DashboardError(status, error.details() or f"the server answered {code.name}", code.name)


class DashboardServer(ThreadingHTTPServer):
    """Serves the page and its API for one yarfd client (gRPC channels are thread-safe)."""

    daemon_threads = True

    def __init__(self, address: tuple[str, int], client: Client, web_dir: Path) -> None:
        if ":" in address[0]:
            self.address_family = socket.AF_INET6
        self.client = client
        self.web_dir = web_dir
        super().__init__(address, DashboardHandler)

    @property
    def url(self) -> str:
        host, port = self.server_address[:2]
        shown = f"[{host}]" if ":" in str(host) else str(host)
        return f"http://{shown}:{port}/"


class DashboardHandler(BaseHTTPRequestHandler):
    server: DashboardServer
    server_version = "yarf-dashboard"

    def do_GET(self) -> None:
        path = urlsplit(self.path).path
        try:
            if path == "/api/jobs":
                jobs = self._call(self.server.client.list)
                self._send_json({"jobs": [job_json(job) for job in jobs]})
            elif match := PREVIEW_PATH.fullmatch(path):
                self._send_preview(unquote(match[1]))
            elif path.startswith("/api/"):
                raise DashboardError(HTTPStatus.NOT_FOUND, f"no API at {path}")
            else:
                self._send_file(path)
        except DashboardError as error:
            self._send_error(error)

    def do_POST(self) -> None:
        path = urlsplit(self.path).path
        try:
            match = ACTION_PATH.fullmatch(path)
            if match is None:
                raise DashboardError(HTTPStatus.NOT_FOUND, f"no API at {path}")
            body = self._json_body()
            job_id, action = unquote(match[1]), match[2]
            client = self.server.client
            if action == "cancel":
                status = self._call(lambda: client.cancel(job_id))
            else:
                priority = body.get("priority")
                if type(priority) is not int or not 1 <= priority <= 100:
                    raise DashboardError(
                        HTTPStatus.BAD_REQUEST, "priority must be a whole number from 1 to 100"
                    )
                status = self._call(lambda: client.set_priority(job_id, priority))
            self._send_json(job_json(status))
        except DashboardError as error:
            self._send_error(error)

    def _call(self, call: Callable[[], _T]) -> _T:
        try:
            return call()
        except grpc.RpcError as error:
            raise _grpc_error(error) from None

    def _json_body(self) -> dict[str, Any]:
        """The request's JSON object. Requiring JSON keeps other sites' plain form posts
        (which a browser sends without asking) from acting on the queue."""
        if self.headers.get_content_type() != "application/json":
            raise DashboardError(HTTPStatus.UNSUPPORTED_MEDIA_TYPE, "send application/json")
        origin = self.headers.get("Origin")
        if origin is not None and urlsplit(origin).netloc != self.headers.get("Host"):
            raise DashboardError(HTTPStatus.FORBIDDEN, f"requests from {origin} are refused")
        length_text = self.headers.get("Content-Length") or "0"
        length = int(length_text) if length_text.isdigit() else -1
        if not 0 <= length <= MAX_BODY_BYTES:
            raise DashboardError(HTTPStatus.BAD_REQUEST, f"send at most {MAX_BODY_BYTES} bytes")
        try:
            body = json.loads(self.rfile.read(length) or b"{}")
        except ValueError:
            raise DashboardError(HTTPStatus.BAD_REQUEST, "the body is not JSON") from None
        if not isinstance(body, dict):
            raise DashboardError(HTTPStatus.BAD_REQUEST, "the body must be a JSON object")
        return body

    def _send_preview(self, job_id: str) -> None:
        reply = self._call(
            lambda: self.server.client.result(job_id, render_pb2.GetResultRequest.PNG)
        )
        if not reply.image:
            raise DashboardError(HTTPStatus.NOT_FOUND, f"job {job_id} has no image yet")
        # An ended job's image is final: the browser may keep it (the page's URL for it
        # names the job's submission time, state and samples, so it never serves another).
        final = reply.status.state in FINAL_STATES
        caching = "private, max-age=86400, immutable" if final else "no-store"
        self._send(HTTPStatus.OK, "image/png", bytes(reply.image), caching)

    def _send_file(self, path: str) -> None:
        # Only the folder's own files, by name: no subfolders, no dot files.
        name = unquote(path).lstrip("/") or "index.html"
        suffix = Path(name).suffix
        file = self.server.web_dir / name
        if "/" in name or "\\" in name or name.startswith(".") or suffix not in CONTENT_TYPES:
            raise DashboardError(HTTPStatus.NOT_FOUND, f"no file {path}")
        try:
            data = file.read_bytes()
        except OSError:
            raise DashboardError(HTTPStatus.NOT_FOUND, f"no file {path}") from None
        self._send(HTTPStatus.OK, CONTENT_TYPES[suffix], data)

    def _send_json(self, value: object, status: HTTPStatus = HTTPStatus.OK) -> None:
        self._send(status, "application/json", json.dumps(value).encode())

    def _send_error(self, error: DashboardError) -> None:
        self._send_json({"error": str(error), "code": error.code}, error.status)

    def _send(
        self, status: HTTPStatus, content_type: str, data: bytes, caching: str = "no-store"
    ) -> None:
        """Sends one answer; by default never reused: jobs change every second."""
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(data)))
        self.send_header("Cache-Control", caching)
        for header, value in SECURITY_HEADERS.items():
            self.send_header(header, value)
        self.end_headers()
        self.wfile.write(data)

    def log_request(self, code: int | str = "-", size: int | str = "-") -> None:
        # The page polls every second; only failures are worth a line.
        if isinstance(code, int) and code >= 400:
            super().log_request(code, size)
