"""``yarf dashboard``: a web page of a yarfd's queue and the JSON API behind it.

The page's files (index.html, app.js, style.css) live in clients/web; this
module serves them and turns a few HTTP requests into RenderService calls:

- ``GET /api/jobs``: ``{"jobs": [job, ...]}``, newest first
- ``GET /api/jobs/<id>``: the job's page: ``{"job", "options", "scene", "log",
  "error", "aovs"}`` (``options`` and ``scene`` null when the yarfd no longer
  keeps them)
- ``GET /api/jobs/<id>/preview.png``: the job's image so far, as PNG
- ``GET /api/jobs/<id>/image.exr`` and ``image.png``: the image as a download
  (the EXR with the job's AOVs as channels NAME.R, NAME.G, NAME.B)
- ``GET /api/jobs/<id>/aov/<name>.png``: one AOV of an ended job, as PNG
- ``POST /api/jobs?file=NAME&spp=N&...`` with the scene file's bytes
  (``application/octet-stream``; the query takes ``yarf submit``'s options):
  submits it; the new job, 201
- ``POST /api/jobs/<id>/cancel``: the job's status after the request
- ``POST /api/jobs/<id>/priority`` with ``{"priority": P}``: the job's new status

A failed call answers ``{"error": message, "code": grpc code}`` with the
HTTP status that matches the gRPC code (NOT_FOUND → 404...).
"""

from __future__ import annotations

import argparse
import json
import re
import socket
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, NoReturn, TypeVar
from urllib.parse import parse_qsl, unquote, urlsplit

import grpc
import numpy as np

from yarf.assets import file_components, is_file_key
from yarf.client import FINAL_STATES, Client
from yarf.images import srgb_bytes
from yarf.render_options import AOV_NAMES, OptionError, add_render_arguments, render_settings
from yarf.scene import (
    IMPORTED_SUFFIXES,
    JSON_SUFFIXES,
    TEXT_SUFFIXES,
    SceneError,
    import_scene,
    iter_shapes,
    load_scene,
)
from yarf.v1 import component_pb2, render_pb2, scene_pb2

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
JOBS_PATH = "/api/jobs"
JOB_PATH = re.compile(r"/api/jobs/([^/]+)")
PREVIEW_PATH = re.compile(r"/api/jobs/([^/]+)/preview\.png")
IMAGE_PATH = re.compile(r"/api/jobs/([^/]+)/image\.(exr|png)")
AOV_PATH = re.compile(r"/api/jobs/([^/]+)/aov/([^/]+)\.png")
ACTION_PATH = re.compile(r"/api/jobs/([^/]+)/(cancel|priority)")
MAX_BODY_BYTES = 4096
# Uploaded scene files: one file with its geometry inline (meshes belong in
# asset uploads, which `yarf submit` makes).
MAX_UPLOAD_BYTES = 16 << 20
# Seconds an uploaded Mitsuba or pbrt file may take to convert: its
# includes and shapes may make far more than its bytes.
IMPORT_SECONDS = 60.0
# A refused upload's body is read (and dropped) up to this size before the
# connection closes, so that the browser gets the answer instead of a reset.
MAX_DRAINED_BYTES = 4 * MAX_UPLOAD_BYTES
SCENE_SUFFIXES = IMPORTED_SUFFIXES + JSON_SUFFIXES + TEXT_SUFFIXES
IMAGE_FORMATS = {"exr": render_pb2.GetResultRequest.EXR, "png": render_pb2.GetResultRequest.PNG}
DOWNLOAD_TYPES = {"exr": "image/x-exr", "png": "image/png"}
# AOVs shown as they are (albedo: a colour, sRGB-encoded as the image is;
# uv: coordinates in [0, 1]); normals mapped from [-1, 1]; the others
# (distances, points, indices) stretched over their range in the image.
SIGNED_UNIT_AOVS = frozenset({"sh_normal", "geo_normal"})
STRETCHED_AOVS = frozenset({"depth", "position", "shape_index", "material_index"})

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


def property_json(value: component_pb2.Property) -> object:
    """A component property as JSON: numbers, switches and text as they are, vectors
    and colours as [x, y, z], a transform as ``{"matrix": its 16 entries}``, a
    reference as ``{"reference": name}``."""
    kind = value.WhichOneof("value")
    if kind in ("vec3_value", "rgb_value"):
        vector = getattr(value, kind)
        return (
            [vector.x, vector.y, vector.z]
            if kind == "vec3_value"
            else [vector.r, vector.g, vector.b]
        )
    if kind == "transform_value":
        return {"matrix": list(value.transform_value.m)}
    if kind == "float_array_value":
        return list(value.float_array_value.values)
    if kind == "reference":
        return {"reference": value.reference}
    return getattr(value, kind) if kind else None


def component_json(spec: scene_pb2.ComponentSpec) -> dict[str, Any] | None:
    """A transport, integrator or sampler choice; None when the scene's is kept."""
    if not spec.class_name and not spec.properties.values and not spec.address:
        return None
    return {
        "class_name": spec.class_name,
        "address": spec.address,
        "properties": {
            key: property_json(spec.properties.values[key])
            for key in sorted(spec.properties.values)
        },
    }


def options_json(options: render_pb2.RenderOptions) -> dict[str, Any]:
    """The parts of a job's RenderOptions a person reads."""
    crop = options.crop if options.HasField("crop") else None
    return {
        "spp": options.spp,
        "seed": options.seed,
        "transport": component_json(options.transport),
        "integrator": component_json(options.integrator),
        "sampler": component_json(options.sampler),
        "crop": None if crop is None else [crop.x0, crop.x1, crop.y0, crop.y1],
        "aovs": list(options.aovs),
        "threads": options.threads,
        "first_sample": options.first_sample,
        "component_retries": options.component_retries,
    }


def scene_json(scene: render_pb2.SceneSummary) -> dict[str, Any]:
    return {
        "width": scene.width,
        "height": scene.height,
        "camera": scene.camera,
        "shapes": scene.shapes,
        "instances": scene.instances,
        "materials": scene.materials,
        "lights": scene.lights,
        "textures": scene.textures,
        "media": scene.media,
    }


def details_json(details: render_pb2.JobDetails) -> dict[str, Any]:
    """The job page's data: status, options and scene (None when not kept), log."""
    kept = details.HasField("options")
    return {
        "job": job_json(details.status),
        "options": options_json(details.options) if kept else None,
        "scene": scene_json(details.scene) if details.HasField("scene") else None,
        "log": list(details.log),
        "error": details.status.error,
        "aovs": list(details.options.aovs),
    }


def aov_display(name: str, values: np.ndarray) -> np.ndarray:
    """An AOV [H, W, 3] as 8-bit values to look at (see SIGNED_UNIT_AOVS, STRETCHED_AOVS)."""
    values = np.nan_to_num(values.astype(np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    if name == "albedo":
        return srgb_bytes(values)
    if name in SIGNED_UNIT_AOVS:
        values = values * 0.5 + 0.5
    elif name in STRETCHED_AOVS:
        # Each channel over its range (a position's axes differ; depth's are one).
        low = values.min(axis=(0, 1), keepdims=True)
        span = values.max(axis=(0, 1), keepdims=True) - low
        values = np.where(span > 0, (values - low) / np.where(span > 0, span, 1.0), 0.0)
    return np.rint(np.clip(values, 0.0, 1.0) * 255.0).astype(np.uint8)


def encode_png(pixels: np.ndarray) -> bytes:
    """8-bit pixels [H, W, 3] as a PNG file's bytes, written by OpenImageIO."""
    import OpenImageIO as oiio  # imported when used: `import yarf` stays light

    with tempfile.TemporaryDirectory(prefix="yarf-") as folder:
        path = Path(folder) / "image.png"
        spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], 3, oiio.UINT8)
        output = oiio.ImageOutput.create(str(path))
        if output is None:
            raise OSError(f"cannot write a PNG image: {oiio.geterror()}")
        try:
            if not output.open(str(path), spec) or not output.write_image(
                np.ascontiguousarray(pixels)
            ):
                raise OSError(f"cannot write a PNG image: {output.geterror()}")
        finally:
            output.close()
        return path.read_bytes()


class _UploadOptionParser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        raise DashboardError(HTTPStatus.BAD_REQUEST, message)


def upload_option_parser() -> argparse.ArgumentParser:
    """The options of an uploaded scene's job: ``yarf submit``'s own (render options as
    render_options.py defines them, ``name``, ``priority``), as query parameters."""
    parser = _UploadOptionParser(prog="POST /api/jobs", add_help=False, allow_abbrev=False)
    add_render_arguments(parser, spp_default="default: the file's, else the server's")
    parser.add_argument("--name")
    parser.add_argument("--priority", type=int)
    return parser


@dataclass(frozen=True)
class UploadedScene:
    """A scene file the browser sent, loaded; its spp (0: none), import warnings and
    crop (as --crop takes it; "": the whole film)."""

    scene: scene_pb2.Scene
    sample_count: int
    warnings: list[str]
    crop: str = ""


def file_references(scene: scene_pb2.Scene) -> list[str]:
    """What ``scene`` names by file (mesh files, and any component's ``filename``)."""
    found = [
        f"{where}: mesh file {shape.mesh.file!r}"
        for where, shape in iter_shapes(scene)
        if shape.WhichOneof("geometry") == "mesh" and shape.mesh.WhichOneof("source") == "file"
    ]
    for where, spec in file_components(scene):
        for key, value in spec.properties.values.items():
            if is_file_key(key) and value.WhichOneof("value") == "string_value":
                found.append(f"{where}: {key} {value.string_value!r}")
    return found


def load_uploaded_scene(data: bytes, file_name: str) -> UploadedScene:
    """Loads an uploaded scene file as ``yarf submit`` loads one of that extension;
    SceneError for a bad file, or one that names other files.

    The file is written alone into a private temporary folder, and the
    importer is confined to it: an include, mesh or spectrum named anywhere
    else is not found, whether it exists or not, so that an upload reads
    nothing of this machine. A message about a file other than the upload
    is withheld all the same, and a scene left naming a file is refused,
    since the dashboard sends only what was uploaded.
    """
    with tempfile.TemporaryDirectory(prefix="yarf-upload-") as folder:
        path = Path(folder) / file_name
        path.write_bytes(data)
        try:
            if path.suffix.lower() in IMPORTED_SUFFIXES:
                imported = import_scene(
                    path, inline_files=False, confine=True, timeout=IMPORT_SECONDS
                )
                scene, spp, warnings = imported.scene, imported.sample_count, imported.warnings
                crop = imported.crop
            else:
                scene, spp, warnings, crop = load_scene(path, inline_files=False), 0, [], ""
        except SceneError as error:
            raise SceneError(_about_upload(str(error), path)) from None
    own = f"{path}:"
    shown = [_about_upload(w, path) for w in warnings if w.startswith(own)]
    references = file_references(scene)
    if references:
        more = f" (and {len(references) - 1} more)" if len(references) > 1 else ""
        raise SceneError(
            f"{file_name}: names {references[0]}{more}: an uploaded scene must be one file with "
            "its meshes and textures inline; `yarf submit` sends a scene with its files"
        )
    return UploadedScene(scene, spp, shown, crop)


_LOCATED = re.compile(r"\S+:\d+: ")


def _about_upload(message: str, path: Path) -> str:
    """An importer's message with the temporary folder left out; withheld when it is
    about another file than the upload."""
    if not message.startswith(f"{path}") and _LOCATED.match(message):
        return (
            f"{path.name}: includes or reads another file, which an uploaded scene cannot "
            "(upload one file that holds the whole scene)"
        )
    folder = str(path.parent)
    return message.replace(folder + "/", "").replace(folder, "the upload's folder")


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
        client = self.server.client
        try:
            if path == JOBS_PATH:
                jobs = self._call(client.list)
                self._send_json({"jobs": [job_json(job) for job in jobs]})
            elif match := JOB_PATH.fullmatch(path):
                job_id = unquote(match[1])
                self._send_json(details_json(self._call(lambda: client.details(job_id))))
            elif match := PREVIEW_PATH.fullmatch(path):
                self._send_preview(unquote(match[1]))
            elif match := IMAGE_PATH.fullmatch(path):
                self._send_download(unquote(match[1]), match[2])
            elif match := AOV_PATH.fullmatch(path):
                self._send_aov(unquote(match[1]), unquote(match[2]))
            elif path.startswith("/api/"):
                raise DashboardError(HTTPStatus.NOT_FOUND, f"no API at {path}")
            else:
                self._send_file(path)
        except DashboardError as error:
            self._send_error(error)

    def do_POST(self) -> None:
        url = urlsplit(self.path)
        try:
            if url.path == JOBS_PATH:
                self._submit_upload(url.query)
                return
            match = ACTION_PATH.fullmatch(url.path)
            if match is None:
                raise DashboardError(HTTPStatus.NOT_FOUND, f"no API at {url.path}")
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

    def _check_origin(self) -> None:
        """Refuses a request a page of another site sent (its Origin is not this host)."""
        origin = self.headers.get("Origin")
        if origin is not None and urlsplit(origin).netloc != self.headers.get("Host"):
            raise DashboardError(HTTPStatus.FORBIDDEN, f"requests from {origin} are refused")

    def _content_length(self) -> int:
        text = self.headers.get("Content-Length") or "0"
        return int(text) if text.isdigit() else -1

    def _json_body(self) -> dict[str, Any]:
        """The request's JSON object. Requiring JSON keeps other sites' plain form posts
        (which a browser sends without asking) from acting on the queue."""
        if self.headers.get_content_type() != "application/json":
            raise DashboardError(HTTPStatus.UNSUPPORTED_MEDIA_TYPE, "send application/json")
        self._check_origin()
        length = self._content_length()
        if not 0 <= length <= MAX_BODY_BYTES:
            raise DashboardError(HTTPStatus.BAD_REQUEST, f"send at most {MAX_BODY_BYTES} bytes")
        try:
            body = json.loads(self.rfile.read(length) or b"{}")
        except ValueError:
            raise DashboardError(HTTPStatus.BAD_REQUEST, "the body is not JSON") from None
        if not isinstance(body, dict):
            raise DashboardError(HTTPStatus.BAD_REQUEST, "the body must be a JSON object")
        return body

    def _upload_body(self) -> bytes:
        """The uploaded file's bytes. application/octet-stream is not a type a form or
        a "simple" cross-site fetch may send: another site's script must ask first
        (a CORS preflight), which this server never grants; its Origin is refused too."""
        if self.headers.get_content_type() != "application/octet-stream":
            raise DashboardError(
                HTTPStatus.UNSUPPORTED_MEDIA_TYPE, "send the scene file as application/octet-stream"
            )
        self._check_origin()
        if "Content-Length" not in self.headers:
            raise DashboardError(HTTPStatus.LENGTH_REQUIRED, "send a Content-Length")
        length = self._content_length()
        if length < 0:
            raise DashboardError(HTTPStatus.BAD_REQUEST, "the Content-Length is not a number")
        if length > MAX_UPLOAD_BYTES:
            raise DashboardError(
                HTTPStatus.REQUEST_ENTITY_TOO_LARGE,
                f"the scene file has {length} bytes; an upload takes at most "
                f"{MAX_UPLOAD_BYTES >> 20} MiB (`yarf submit` sends larger scenes)",
            )
        data = self.rfile.read(length)
        if len(data) != length:
            raise DashboardError(HTTPStatus.BAD_REQUEST, "the upload ended early")
        if not data:
            raise DashboardError(HTTPStatus.BAD_REQUEST, "the scene file is empty")
        return data

    def _submit_upload(self, query: str) -> None:
        """Loads the uploaded scene as `yarf submit` would, and submits it."""
        try:
            data = self._upload_body()
        except DashboardError:
            self._drain_body()
            raise
        parameters = parse_qsl(query, keep_blank_values=True)
        file_name = next((value for key, value in parameters if key == "file"), "")
        suffix = Path(file_name).suffix.lower()
        if not file_name:
            raise DashboardError(HTTPStatus.BAD_REQUEST, "name the scene file: ?file=NAME")
        if suffix not in SCENE_SUFFIXES:
            raise DashboardError(
                HTTPStatus.BAD_REQUEST,
                f"{file_name}: a scene file ends in one of {', '.join(SCENE_SUFFIXES)}",
            )
        argv = [f"--{key.replace('_', '-')}={value}" for key, value in parameters if key != "file"]
        args = upload_option_parser().parse_args(argv)
        if args.priority is not None and not 1 <= args.priority <= 100:
            raise DashboardError(HTTPStatus.BAD_REQUEST, "priority must be 1 to 100")
        try:
            settings = render_settings(args)
            if settings.time_limit is not None:
                raise OptionError(
                    "time_limit", "a job submitted here has no time limit (cancel it instead)"
                )
            # Its own name only: the folder it came from is the browser's business.
            safe_name = re.sub(r"[^\w.+-]", "_", Path(file_name).name).lstrip(".") or "scene"
            uploaded = load_uploaded_scene(data, safe_name[: -len(suffix)] + suffix)
            job = settings.prepare(
                uploaded.scene, default_spp=uploaded.sample_count, default_crop=uploaded.crop
            )
        except (OptionError, SceneError) as error:
            raise DashboardError(HTTPStatus.BAD_REQUEST, str(error)) from None
        client = self.server.client
        job_id = self._call(
            lambda: client.submit(
                job.scene,
                job.spp,
                settings.seed,
                name=args.name or Path(file_name).name,
                transport=job.transport,
                crop=job.crop,
                aovs=job.aovs,
                priority=args.priority,
            )
        )
        reply = job_json(self._call(lambda: client.status(job_id)))
        reply["warnings"] = uploaded.warnings
        self._send_json(reply, HTTPStatus.CREATED)

    def _drain_body(self) -> None:
        """Reads a refused request's body (up to MAX_DRAINED_BYTES) so that closing the
        connection does not reset it before the browser reads the answer."""
        self.close_connection = True
        left = min(max(self._content_length(), 0), MAX_DRAINED_BYTES)
        while left > 0:
            block = self.rfile.read(min(left, 1 << 20))
            if not block:
                break
            left -= len(block)

    def _send_preview(self, job_id: str) -> None:
        reply = self._call(
            lambda: self.server.client.result(job_id, render_pb2.GetResultRequest.PNG)
        )
        if not reply.image:
            raise DashboardError(HTTPStatus.NOT_FOUND, f"job {job_id} has no image yet")
        self._send(HTTPStatus.OK, "image/png", bytes(reply.image), _caching(reply.status))

    def _send_download(self, job_id: str, extension: str) -> None:
        reply = self._call(lambda: self.server.client.result(job_id, IMAGE_FORMATS[extension]))
        if not reply.image:
            raise DashboardError(HTTPStatus.NOT_FOUND, f"job {job_id} has no image yet")
        file_name = re.sub(r"[^\w.-]", "_", job_id) + "." + extension
        self._send(
            HTTPStatus.OK,
            DOWNLOAD_TYPES[extension],
            bytes(reply.image),
            "no-store",
            {"Content-Disposition": f'attachment; filename="{file_name}"'},
        )

    def _send_aov(self, job_id: str, name: str) -> None:
        if name not in AOV_NAMES:
            raise DashboardError(
                HTTPStatus.NOT_FOUND, f"no AOV {name!r} (known: {', '.join(AOV_NAMES)})"
            )
        try:
            status, _, aovs, _ = self._call(lambda: self.server.client.image_layers(job_id))
        except RuntimeError as error:  # no image yet
            raise DashboardError(HTTPStatus.CONFLICT, str(error)) from None
        if name not in aovs:
            why = "did not ask for it" if status.state in FINAL_STATES else "has not ended"
            raise DashboardError(HTTPStatus.NOT_FOUND, f"job {job_id} has no {name} AOV: it {why}")
        data = encode_png(aov_display(name, aovs[name]))
        self._send(HTTPStatus.OK, "image/png", data, _caching(status))

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
        self,
        status: HTTPStatus,
        content_type: str,
        data: bytes,
        caching: str = "no-store",
        headers: dict[str, str] | None = None,
    ) -> None:
        """Sends one answer; by default never reused: jobs change every second."""
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(data)))
        self.send_header("Cache-Control", caching)
        for header, value in {**SECURITY_HEADERS, **(headers or {})}.items():
            self.send_header(header, value)
        self.end_headers()
        self.wfile.write(data)

    def log_request(self, code: int | str = "-", size: int | str = "-") -> None:
        # The page polls every second; only failures are worth a line.
        if isinstance(code, int) and code >= 400:
            super().log_request(code, size)


def _caching(status: render_pb2.JobStatus) -> str:
    """An ended job's images are final: the browser may keep them (the page's URLs for
    them name the job's submission time, state and samples, so they never serve another)."""
    return "private, max-age=86400, immutable" if status.state in FINAL_STATES else "no-store"
