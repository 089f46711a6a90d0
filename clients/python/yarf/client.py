"""A typed client of yarfd's services over one gRPC channel."""

from __future__ import annotations

import time
import warnings
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Any, Self

import grpc
import numpy as np
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

from yarf import denoise as denoising
from yarf.assets import AssetData, asset_chunks, sha256_of
from yarf.credentials import open_channel
from yarf.images import decode_exr_layers, write_image
from yarf.render_options import CropWindow, ImageSettings, RenderSettings, Tonemap
from yarf.v1 import (
    asset_pb2,
    asset_pb2_grpc,
    component_pb2,
    component_pb2_grpc,
    render_pb2,
    render_pb2_grpc,
    scene_pb2,
)

# Scenes with inline meshes and float images of large films are big messages.
MAX_MESSAGE_BYTES = 256 * 1024 * 1024
DEFAULT_ADDRESS = "127.0.0.1:50051"
# Deadline of unary calls, seconds.
DEFAULT_TIMEOUT = 60.0

FINAL_STATES = frozenset({render_pb2.SUCCEEDED, render_pb2.FAILED, render_pb2.CANCELLED})
# GetResult's file formats, by the extension of the file to write.
IMAGE_FORMATS: dict[str, int] = {
    ".exr": render_pb2.GetResultRequest.EXR,
    ".png": render_pb2.GetResultRequest.PNG,
}

_NUMPY_DTYPES: dict[int, np.dtype[Any]] = {
    component_pb2.Array.FLOAT32: np.dtype("<f4"),
    component_pb2.Array.INT32: np.dtype("<i4"),
    component_pb2.Array.UINT32: np.dtype("<u4"),
}


class SubmitWarning(UserWarning):
    """What the server runs as asked but not at its best (SubmitReply.warnings),
    e.g. a Sobol sampler at a sample count that is not a power of two."""


class RenderError(RuntimeError):
    """A job that ended FAILED or CANCELLED; ``status`` holds its last JobStatus."""

    def __init__(self, status: render_pb2.JobStatus, reason: str = "") -> None:
        state = render_pb2.JobState.Name(status.state)
        message = f"job {status.job_id} {state}"
        if reason or status.error:
            message += f": {reason or status.error}"
        super().__init__(message)
        self.status = status


def check_ended(status: render_pb2.JobStatus, time_limit: float | None, elapsed: float) -> None:
    """Raises RenderError unless the job SUCCEEDED, or its ``time_limit`` (seconds)
    stopped it after at least one sample pass."""
    if status.state == render_pb2.SUCCEEDED:
        return
    if status.state == render_pb2.CANCELLED and time_limit is not None and elapsed >= time_limit:
        if status.samples_done > 0:
            return
        raise RenderError(
            status, f"the time limit of {time_limit:g} s ended before the first sample pass"
        )
    raise RenderError(status)


@dataclass(frozen=True)
class RenderResult:
    """A job's image: ``pixels`` and ``variance`` are float32 arrays [H, W, 3].

    ``aovs`` maps each arbitrary output variable the job asked for
    (RenderOptions.aovs: "albedo", "sh_normal", "depth"...) to its float32
    [H, W, 3] image, once the job has ended.
    """

    status: render_pb2.JobStatus
    pixels: np.ndarray
    variance: np.ndarray
    aovs: dict[str, np.ndarray] = field(default_factory=dict)


def array_to_numpy(array: component_pb2.Array) -> np.ndarray:
    """Copies a yarf.v1.Array into a numpy array of its dtype and shape."""
    dtype = _NUMPY_DTYPES.get(array.dtype)
    if dtype is None:
        raise ValueError(f"Array has no dtype ({array.dtype})")
    shape = tuple(array.shape)
    values = np.frombuffer(array.data, dtype=dtype)
    if values.size != int(np.prod(shape, dtype=np.int64)):
        raise ValueError(f"Array of shape {shape} carries {values.size} elements")
    return values.reshape(shape).astype(dtype.newbyteorder("="), copy=True)


def numpy_to_array(values: np.ndarray) -> component_pb2.Array:
    """A yarf.v1.Array of a float32, int32 or uint32 numpy array."""
    for code, dtype in _NUMPY_DTYPES.items():
        if values.dtype.kind == dtype.kind and values.dtype.itemsize == dtype.itemsize:
            return component_pb2.Array(
                dtype=code,  # type: ignore[arg-type]
                shape=list(values.shape),
                data=np.ascontiguousarray(values, dtype=dtype).tobytes(),
            )
    raise TypeError(f"no yarf.v1.Array dtype for {values.dtype}")


def _health_messages() -> tuple[type[Any], type[Any]]:
    """grpc.health.v1 request and response classes, in a private descriptor pool.

    The two messages of the standard health protocol are declared here so
    that the client needs no grpcio-health-checking package.
    """
    field = descriptor_pb2.FieldDescriptorProto
    file = descriptor_pb2.FileDescriptorProto(
        name="grpc/health/v1/health.proto", package="grpc.health.v1", syntax="proto3"
    )
    request = file.message_type.add(name="HealthCheckRequest")
    request.field.add(name="service", number=1, type=field.TYPE_STRING, label=field.LABEL_OPTIONAL)
    response = file.message_type.add(name="HealthCheckResponse")
    status = response.enum_type.add(name="ServingStatus")
    for number, name in enumerate(("UNKNOWN", "SERVING", "NOT_SERVING", "SERVICE_UNKNOWN")):
        status.value.add(name=name, number=number)
    response.field.add(
        name="status",
        number=1,
        type=field.TYPE_ENUM,
        label=field.LABEL_OPTIONAL,
        type_name=".grpc.health.v1.HealthCheckResponse.ServingStatus",
    )
    pool = descriptor_pool.DescriptorPool()
    pool.Add(file)
    return tuple(  # type: ignore[return-value]
        message_factory.GetMessageClass(pool.FindMessageTypeByName(f"grpc.health.v1.{name}"))
        for name in ("HealthCheckRequest", "HealthCheckResponse")
    )


_HealthCheckRequest, _HealthCheckResponse = _health_messages()


class Client:
    """yarfd's RenderService, AssetService, Registry, Component, Factory and health on one channel.

    Unary calls carry a deadline of ``timeout`` seconds; rpc failures raise
    ``grpc.RpcError`` (its ``code()`` and ``details()`` say why).

    A server beyond loopback wants TLS and a bearer ``token``; ``tls_ca`` is
    the PEM file of the CA (or self-signed certificate) to trust. ``None``
    reads them from $YARF_TOKEN and $YARF_TLS_CA, ``""`` means none. With
    neither the channel is plaintext.
    """

    def __init__(
        self,
        address: str = DEFAULT_ADDRESS,
        *,
        timeout: float = DEFAULT_TIMEOUT,
        token: str | None = None,
        tls_ca: str | Path | None = None,
    ) -> None:
        self.address = address
        self.timeout = timeout
        self._channel = open_channel(
            address,
            [
                ("grpc.max_send_message_length", MAX_MESSAGE_BYTES),
                ("grpc.max_receive_message_length", MAX_MESSAGE_BYTES),
            ],
            token=token,
            tls_ca=tls_ca,
        )
        self.render_service = render_pb2_grpc.RenderServiceStub(self._channel)
        self.registry = component_pb2_grpc.RegistryStub(self._channel)
        self.component = component_pb2_grpc.ComponentStub(self._channel)
        self.factory = component_pb2_grpc.FactoryStub(self._channel)
        self.asset_service = asset_pb2_grpc.AssetServiceStub(self._channel)
        self._health_check = self._channel.unary_unary(
            "/grpc.health.v1.Health/Check",
            request_serializer=_HealthCheckRequest.SerializeToString,
            response_deserializer=_HealthCheckResponse.FromString,
        )

    @property
    def channel(self) -> grpc.Channel:
        return self._channel

    def close(self) -> None:
        self._channel.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()

    # Health.

    def health(self, service: str = "", *, timeout: float | None = None) -> str:
        """The serving status name ("SERVING", "NOT_SERVING"...) of the server or a service."""
        reply = self._health_check(
            _HealthCheckRequest(service=service), timeout=timeout or self.timeout
        )
        return _HealthCheckResponse.ServingStatus.Name(reply.status)

    def is_serving(self, *, timeout: float = 1.0) -> bool:
        """Whether the server answers the health check with SERVING within ``timeout``."""
        try:
            return self.health(timeout=timeout) == "SERVING"
        except grpc.RpcError:
            return False

    # Jobs.

    def submit(
        self,
        scene: scene_pb2.Scene,
        spp: int = 16,
        seed: int = 0,
        *,
        name: str = "",
        transport: scene_pb2.ComponentSpec | None = None,
        integrator: scene_pb2.ComponentSpec | None = None,
        sampler: scene_pb2.ComponentSpec | None = None,
        component_retries: int = 0,
        component_timeout: float = 0.0,
        priority: int | None = None,
        max_retries: int | None = None,
        crop: render_pb2.PixelWindow | None = None,
        aovs: Sequence[str] = (),
        threads: int = 0,
    ) -> str:
        """Queues a render of ``scene``; returns the job id. What the server
        warns of comes as a SubmitWarning each.

        ``component_retries`` and ``component_timeout`` (seconds, 0: the
        server's 60) govern calls to components in other processes.
        ``priority`` (1..100, None: the server's 50) orders the queue;
        ``max_retries`` (None: 0) requeues a job that failed. ``crop``: only
        these pixels get samples. ``aovs``: arbitrary output variables
        rendered beside the image (RenderOptions.aovs). ``threads``: the job's
        worker threads on the server (0: all of the server's).
        """
        options = render_pb2.RenderOptions(
            spp=spp,
            seed=seed,
            component_retries=component_retries,
            component_timeout_seconds=component_timeout,
            aovs=list(aovs),
            threads=threads,
        )
        if transport is not None:
            options.transport.CopyFrom(transport)
        if integrator is not None:
            options.integrator.CopyFrom(integrator)
        if sampler is not None:
            options.sampler.CopyFrom(sampler)
        if crop is not None:
            options.crop.CopyFrom(crop)
        request = render_pb2.SubmitRequest(
            scene=scene,
            options=options,
            name=name,
            priority=priority or 0,
            max_retries=max_retries or 0,
        )
        reply = self.render_service.Submit(request, timeout=self.timeout)
        for warning in reply.warnings:
            warnings.warn(warning, SubmitWarning, stacklevel=2)
        return str(reply.job_id)

    def watch(self, job_id: str, *, timeout: float | None = None) -> Iterator[render_pb2.JobStatus]:
        """The job's status now, then after every sample pass, until the job ends."""
        stream = self.render_service.Watch(render_pb2.WatchRequest(job_id=job_id), timeout=timeout)
        try:
            yield from stream
        finally:
            stream.cancel()

    def status(self, job_id: str) -> render_pb2.JobStatus:
        """The job's current status (the first message of Watch)."""
        request = render_pb2.WatchRequest(job_id=job_id)
        stream = self.render_service.Watch(request, timeout=self.timeout)
        try:
            for status in stream:
                return status
        finally:
            stream.cancel()
        raise RuntimeError(f"Watch of job {job_id} ended without a status")

    def wait(self, job_id: str, *, timeout: float | None = None) -> render_pb2.JobStatus:
        """Blocks until the job ends; returns its final status."""
        last: render_pb2.JobStatus | None = None
        for status in self.watch(job_id, timeout=timeout):
            last = status
        if last is None or last.state not in FINAL_STATES:
            # The stream ended early (e.g. the server went away): ask once more.
            last = self.status(job_id)
        return last

    def result(
        self, job_id: str, format: int = render_pb2.GetResultRequest.RAW
    ) -> render_pb2.GetResultReply:
        """GetResult: RAW float arrays, or the EXR / PNG file bytes in ``image``."""
        request = render_pb2.GetResultRequest(job_id=job_id, format=format)  # type: ignore[arg-type]
        return self.render_service.GetResult(request, timeout=self.timeout)

    def raw(self, job_id: str) -> RenderResult:
        """The job's pixels and per-pixel variance (finished or progressive so far)."""
        reply = self.result(job_id, render_pb2.GetResultRequest.RAW)
        return RenderResult(
            status=reply.status,
            pixels=array_to_numpy(reply.pixels),
            variance=array_to_numpy(reply.variance),
            aovs={layer.name: array_to_numpy(layer.pixels) for layer in reply.aovs},
        )

    def image(self, job_id: str) -> np.ndarray:
        """The job's pixel estimates, float32 [H, W, 3]."""
        return array_to_numpy(self.result(job_id).pixels)

    def variance(self, job_id: str) -> np.ndarray:
        """The variance of each pixel's estimate, float32 [H, W, 3]."""
        return array_to_numpy(self.result(job_id).variance)

    def image_pixels(self, job_id: str) -> tuple[render_pb2.JobStatus, np.ndarray, bool]:
        """The job's status, its pixel estimates float32 [H, W, 3] for an image file,
        and whether they are exact: a film too large for float pixels in one reply
        (about 11 million pixels) comes as the server's half-float EXR.

        Raises RuntimeError when the job has no image yet.
        """
        status, pixels, _, exact = self.image_layers(job_id)
        return status, pixels, exact

    def image_layers(
        self, job_id: str
    ) -> tuple[render_pb2.JobStatus, np.ndarray, dict[str, np.ndarray], bool]:
        """As ``image_pixels``, with the job's AOVs by name (float32 [H, W, 3], once
        it has ended) between the pixels and whether they are exact.
        """
        try:
            try:
                reply = self.result(job_id)
                aovs = {layer.name: array_to_numpy(layer.pixels) for layer in reply.aovs}
                return reply.status, array_to_numpy(reply.pixels), aovs, True
            except grpc.RpcError as error:
                too_large = isinstance(error, grpc.Call) and (
                    error.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
                )
                if not too_large:
                    raise
            reply = self.result(job_id, render_pb2.GetResultRequest.EXR)
            pixels, aovs = decode_exr_layers(reply.image)
            return reply.status, pixels, aovs, False
        except grpc.RpcError as error:
            if isinstance(error, grpc.Call) and error.code() == grpc.StatusCode.FAILED_PRECONDITION:
                raise RuntimeError(f"job {job_id} has no image yet ({error.details()})") from None
            raise

    def encoded(self, job_id: str, format: int) -> bytes:
        """The job's image as an EXR or PNG file."""
        return bytes(self.result(job_id, format).image)

    def fetch(
        self,
        job_id: str,
        path: str | Path,
        *,
        half: bool = False,
        exposure: float = 0.0,
        tonemap: Tonemap = "linear",
        denoise: bool = False,
    ) -> render_pb2.JobStatus:
        """Writes the job's image (final or progressive) to ``path``, an .exr or .png file.

        An EXR holds 32-bit floats (``half``: 16-bit) and the job's AOVs as
        channels NAME.R, NAME.G, NAME.B; a PNG the radiance scaled by
        2^``exposure`` and mapped by ``tonemap`` ("linear" or "aces"),
        sRGB-encoded. The image of a job with a crop window holds the window
        alone, as ``yarf render --crop`` writes it. ``denoise``: the image
        denoised here with the job's albedo and sh_normal AOVs
        (yarf.denoise). Returns the job's status
        when the image was taken; raises ValueError for another extension
        or a bad setting, RuntimeError when the job has no image yet, and
        DenoiseError when it cannot be denoised.
        """
        path = Path(path)
        if path.suffix.lower() not in IMAGE_FORMATS:
            raise ValueError(
                f"cannot write {path}: the extension must be one of {', '.join(IMAGE_FORMATS)}"
            )
        settings = ImageSettings(half=half, exposure=exposure, tonemap=tonemap)
        settings.check(path.suffix.lower())
        if denoise:
            denoising.denoiser()
        status, pixels, aovs, _ = self.image_layers(job_id)
        window = self.crop_window(job_id)
        if denoise:
            missing = denoising.missing_aovs(aovs)
            if missing:
                raise denoising.DenoiseError(
                    f"job {job_id} has no {' and '.join(missing)} AOV to denoise with "
                    "(submit it with --aov albedo,sh_normal; a job that did not end has none)"
                )
            pixels = denoising.denoise(pixels, aovs, window=window)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_image(path, pixels, settings, window=window, aovs=aovs)
        return status

    def crop_window(self, job_id: str) -> render_pb2.PixelWindow | None:
        """The job's crop window (RenderOptions.crop); None for the whole film, and
        from a server without GetJob."""
        try:
            options = self.details(job_id).options
        except grpc.RpcError as error:
            if isinstance(error, grpc.Call) and error.code() == grpc.StatusCode.UNIMPLEMENTED:
                return None
            raise
        return options.crop if options.HasField("crop") else None

    def watch_within(self, job_id: str, time_limit: float | None) -> Iterator[render_pb2.JobStatus]:
        """The job's statuses as ``watch`` gives them; at ``time_limit`` seconds (None:
        never) the job is cancelled, and its statuses follow until it ends, with the
        samples done so far."""
        try:
            yield from self.watch(job_id, timeout=time_limit)
        except grpc.RpcError as error:
            expired = isinstance(error, grpc.Call) and (
                error.code() == grpc.StatusCode.DEADLINE_EXCEEDED
            )
            if time_limit is None or not expired:
                raise
            self.cancel(job_id)
            yield from self.watch(job_id, timeout=self.timeout)

    def render(
        self,
        scene: scene_pb2.Scene,
        spp: int = 16,
        seed: int = 0,
        *,
        name: str = "",
        transport: str | scene_pb2.ComponentSpec | None = None,
        integrator: scene_pb2.ComponentSpec | None = None,
        sampler: scene_pb2.ComponentSpec | None = None,
        timeout: float | None = None,
        res: str | tuple[int, int] | None = None,
        crop: str | tuple[float, float, float, float] | CropWindow | None = None,
        time_limit: float | None = None,
        max_depth: int | None = None,
        materials: Mapping[str, str] | None = None,
        aovs: str | Sequence[str] = (),
        threads: int | None = None,
    ) -> RenderResult:
        """Submits, waits (at most ``timeout`` s) and fetches the image.

        The options are those of ``yarf render`` (``RenderSettings``):
        ``res`` (width, height) or "WxH" sets the film size; ``crop`` (x0,
        x1, y0, y1) in pixels, or in fractions of the film when floats,
        renders only that window and returns its pixels alone;
        ``time_limit`` seconds after the submission the job is cancelled and
        the image holds the samples done by then; ``transport``
        ("CLASS[@ADDRESS]" or a ComponentSpec) and ``max_depth`` choose the
        light transport; ``materials`` maps a material's name (or class) to
        the class it becomes; ``aovs`` names arbitrary output variables
        rendered beside the image (RenderResult.aovs; any of AOV_NAMES, as a
        list or "albedo,depth"); ``threads`` caps the job's worker threads on
        the server. A bad value raises
        OptionError (a ValueError) before anything is submitted.

        Raises RenderError unless the job SUCCEEDED, or was stopped by its
        time limit after at least one sample pass.
        """
        settings = RenderSettings.of(
            spp=spp,
            seed=seed,
            res=res,
            crop=crop,
            time_limit=time_limit,
            transport=transport,
            materials=materials,
            max_depth=max_depth,
            aovs=aovs,
            threads=threads,
        )
        job = settings.prepare(scene)
        job_id = self.submit(
            job.scene,
            job.spp,
            seed,
            name=name,
            transport=job.transport,
            integrator=integrator,
            sampler=sampler,
            crop=job.crop,
            aovs=job.aovs,
            threads=job.threads,
        )
        started = time.monotonic()
        last: render_pb2.JobStatus | None = None
        if timeout is not None and (time_limit is None or timeout < time_limit):
            statuses = self.watch(job_id, timeout=timeout)
        else:
            statuses = self.watch_within(job_id, time_limit)
        for last in statuses:  # noqa: B007 - the last status is the one kept
            pass
        status = last if last is not None and last.state in FINAL_STATES else self.status(job_id)
        check_ended(status, time_limit, time.monotonic() - started)
        result = self.raw(job_id)
        if job.crop is None:
            return result
        window = (slice(job.crop.y0, job.crop.y1), slice(job.crop.x0, job.crop.x1))
        return RenderResult(
            result.status,
            result.pixels[window],
            result.variance[window],
            {name: image[window] for name, image in result.aovs.items()},
        )

    def cancel(self, job_id: str) -> render_pb2.JobStatus:
        """Asks the job to stop; it ends CANCELLED within a second."""
        reply = self.render_service.Cancel(
            render_pb2.CancelRequest(job_id=job_id), timeout=self.timeout
        )
        return reply.status

    def list(self) -> list[render_pb2.JobStatus]:
        """Every job the server knows, newest first."""
        reply = self.render_service.List(render_pb2.ListJobsRequest(), timeout=self.timeout)
        return list(reply.jobs)

    def set_priority(self, job_id: str, priority: int) -> render_pb2.JobStatus:
        """Moves a queued job in the queue (1..100); returns its status."""
        request = render_pb2.SetPriorityRequest(job_id=job_id, priority=priority)
        return self.render_service.SetPriority(request, timeout=self.timeout)

    def details(self, job_id: str) -> render_pb2.JobDetails:
        """The job's options as it runs, a summary of its scene and its event log."""
        request = render_pb2.GetJobRequest(job_id=job_id)
        return self.render_service.GetJob(request, timeout=self.timeout)

    # Assets.

    def missing_assets(self, hashes: Iterable[str]) -> list[str]:
        """Which of the SHA-256 ``hashes`` the server does not hold, in the order given."""
        request = asset_pb2.MissingAssetsRequest(sha256=list(hashes))
        return list(self.asset_service.Missing(request, timeout=self.timeout).sha256)

    def upload_asset(
        self, source: AssetData, *, sha256: str | None = None, timeout: float | None = None
    ) -> str:
        """Uploads bytes, or a file read as it is sent, in 1 MiB chunks; returns the SHA-256.

        ``sha256``: the hash when known already (the server checks it).
        The server keeps one copy however often the same bytes arrive.
        """
        digest = sha256 or sha256_of(source)
        self.asset_service.Upload(asset_chunks(source, digest), timeout=timeout)
        return digest

    # Components.

    def list_classes(self) -> component_pb2.ListClassesReply:
        """Classes the server can make, and the plugins that failed to load."""
        return self.registry.ListClasses(component_pb2.ListClassesRequest(), timeout=self.timeout)

    def load_plugin(self, path: str) -> list[component_pb2.ComponentInfo]:
        """Loads a plugin (a path on the server's machine); returns its classes."""
        reply = self.registry.LoadPlugin(
            component_pb2.LoadPluginRequest(path=path), timeout=self.timeout
        )
        return list(reply.classes)

    def describe(self, class_name: str = "", *, handle: int = 0) -> component_pb2.ComponentInfo:
        """Class name, version and interfaces of a class or instance."""
        request = component_pb2.DescribeRequest(class_name=class_name, handle=handle)
        return self.component.Describe(request, timeout=self.timeout)

    def create(
        self, class_name: str, properties: component_pb2.Properties | None = None
    ) -> component_pb2.CreateReply:
        """Makes an instance; the reply holds its handle."""
        request = component_pb2.CreateRequest(class_name=class_name, properties=properties)
        return self.factory.Create(request, timeout=self.timeout)

    def release(self, handle: int) -> None:
        """Ends an instance made by ``create``."""
        self.factory.Release(component_pb2.ReleaseRequest(handle=handle), timeout=self.timeout)
