"""The scene of a running job, for transports: yarfd's SceneView, Intersect,
Shape, SampleSurfaceArea, SampleSurfaceDirection, SurfaceModel, Emitter and
Medium services as numpy calls: what the kernel's own transports ask of their scene.

A Transport's ``prepare`` and ``evaluate`` receive a SceneView bound to the
yarfd that called them and to the job's scene handle. Arrays are float32,
one row per ray or point, world space; failures raise SceneViewError naming
the call. Materials are SurfaceClients (job_surface.py), lights'
emitters EmitterClients (job_emitter.py), media MediumClients (job_medium.py).
"""

from __future__ import annotations

import functools
import threading
from dataclasses import dataclass
from typing import NamedTuple, TypeVar

import numpy as np
from google.protobuf.message import Message

from yarf.client import array_to_numpy, numpy_to_array
from yarf.v1 import geometry_pb2, geometry_pb2_grpc, transport_pb2, transport_pb2_grpc
from yarf_component.channels import channel
from yarf_component.job_calls import Caller, Pending, float_array, ray_batch
from yarf_component.job_emitter import EmitterClient
from yarf_component.job_medium import MediumClient
from yarf_component.job_surface import SurfaceClient

# shape_ids of a ray that hit nothing; also "none" in the emitter, shape and medium
# indices of the replies below.
MISS = 0xFFFFFFFF
NONE = MISS
# LightPoints.flags bits.
DELTA_POSITION, AT_INFINITY, DELTA_DIRECTION = 1, 2, 4
# Deadline of each call, seconds.
DEFAULT_TIMEOUT = 60.0


Decoded = TypeVar("Decoded", bound=tuple)


def _decoded(cls: type[Decoded], reply: Message) -> Decoded:
    """The NamedTuple ``cls`` of the reply's arrays of the same names."""
    return cls(*(array_to_numpy(getattr(reply, name)) for name in cls._fields))  # type: ignore[attr-defined]


def _light_samples(reply: transport_pb2.SampleLightsReply) -> LightSamples:
    samples = _decoded(LightSamples, reply)
    return samples._replace(delta=samples.delta != 0)


class Rays(NamedTuple):
    """A batch of rays: origins and unit directions [N,3], times [N] in the shutter (or None)."""

    origins: np.ndarray
    directions: np.ndarray
    times: np.ndarray | None = None


class Hits(NamedTuple):
    """What Intersect found: t [N] (+inf: miss), geometric normals [N,3] on the shape's
    outward side, uv [N,2], shape_ids [N] (MISS: nothing hit), primitive_ids [N]."""

    t: np.ndarray
    normals: np.ndarray
    uv: np.ndarray
    shape_ids: np.ndarray
    primitive_ids: np.ndarray

    @property
    def found(self) -> np.ndarray:
        """[N] bool: the rays that hit something."""
        return self.shape_ids != MISS

    def take(self, rows: np.ndarray) -> Hits:
        """The hits of the rows selected (a boolean mask or indices)."""
        return Hits(*(a[rows] for a in self))


class Crossings(NamedTuple):
    """Every hit along N rays: ray i owns rows offsets[i]..offsets[i+1]-1 (offsets [N+1])
    of the distances t [M], increasing, and shape_ids [M]."""

    offsets: np.ndarray
    t: np.ndarray
    shape_ids: np.ndarray

    def of(self, ray: int) -> tuple[np.ndarray, np.ndarray]:
        """The distances and shapes of ray ``ray``'s hits."""
        rows = slice(int(self.offsets[ray]), int(self.offsets[ray + 1]))
        return self.t[rows], self.shape_ids[rows]


class LightSamples(NamedTuple):
    """Lights seen from points: unit directions [N,3] toward the light samples, their
    distances [N] (inf at infinity), the unoccluded radiance arriving [N,3], the
    solid-angle pdf [N] (0: nothing sampled; a point light's: the choice's
    probability) and delta [N] bool (point and directional lights: no MIS); the
    light's emitter [N] (an index of ``layout.emitter_handles``, NONE: nothing), its
    point and normal [N,3], its shape [N] (NONE: not a surface) and uv [N,2]."""

    directions: np.ndarray
    distances: np.ndarray
    radiance: np.ndarray
    pdf: np.ndarray
    delta: np.ndarray
    emitters: np.ndarray
    positions: np.ndarray
    normals: np.ndarray
    shape_ids: np.ndarray
    uv: np.ndarray


class LightPoints(NamedTuple):
    """Points on the lights, for paths that start there: positions and normals [N,3]
    (zero at infinity: see ``infinite_light_origins``), pdf [N] (per unit area on a
    surface, the choice's probability for a point light or a light at infinity; 0:
    nothing), flags [N] (DELTA_POSITION, AT_INFINITY, DELTA_DIRECTION), the emitter's
    local frame in the world [N,3,3] (rows s, t, n), emitters [N] (indices of
    ``layout.emitter_handles``), shape_ids [N] and uv [N,2]."""

    positions: np.ndarray
    normals: np.ndarray
    pdf: np.ndarray
    flags: np.ndarray
    frames: np.ndarray
    emitters: np.ndarray
    shape_ids: np.ndarray
    uv: np.ndarray


class CameraConnections(NamedTuple):
    """Points seen by the camera: connected [N] bool, the lens points [N,3] the
    connections end at, raster positions [N,2] in pixels and the importance W [N]
    (radiance L toward the lens at distance d, cosine cos_p, splats L W cos_p / d²)."""

    connected: np.ndarray
    lens_points: np.ndarray
    raster: np.ndarray
    importance: np.ndarray


class SurfaceSamples(NamedTuple):
    """Points sampled on a shape: positions [N,3], unit normals [N,3] on the side the
    shape's normals face, densities [N] (per unit area, or per solid angle at the
    reference points; 0: nothing sampled), uv [N,2] and primitive_ids [N]."""

    positions: np.ndarray
    normals: np.ndarray
    pdf: np.ndarray
    uv: np.ndarray
    primitive_ids: np.ndarray


@dataclass(frozen=True)
class SceneLayout:
    """The scene as a whole: the film size; per shape its material's SurfaceModel
    handle, whether it emits and its emitter (an index of ``emitter_handles``), its
    primitive count and its media (boundary flag, interior and exterior: indices of
    ``medium_handles``); the lights; the camera."""

    width: int
    height: int
    material_handles: np.ndarray
    emits: np.ndarray
    shape_emitters: np.ndarray
    primitive_counts: np.ndarray
    media_boundaries: np.ndarray
    interior_media: np.ndarray
    exterior_media: np.ndarray
    has_lights: bool
    has_environment: bool
    light_count: int
    emitter_handles: np.ndarray
    medium_handles: np.ndarray
    camera_medium: int
    camera_has_lens: bool
    camera_unreachable_reason: str


def _emitted(reply: transport_pb2.EmissionReply) -> tuple[np.ndarray, np.ndarray]:
    return array_to_numpy(reply.radiance), array_to_numpy(reply.pdf)


class SceneView:
    """Scene ``handle`` of a job on the yarfd at ``address``."""

    def __init__(self, address: str, handle: int, *, timeout: float = DEFAULT_TIMEOUT) -> None:
        self.address = address
        self.handle = handle
        self._call = Caller(address, timeout)
        rpc_channel = channel(address)
        self._scene = transport_pb2_grpc.SceneViewStub(rpc_channel)
        self._intersect = geometry_pb2_grpc.IntersectStub(rpc_channel)
        self._shape = geometry_pb2_grpc.ShapeStub(rpc_channel)
        self._by_area = geometry_pb2_grpc.SampleSurfaceAreaStub(rpc_channel)
        self._by_direction = geometry_pb2_grpc.SampleSurfaceDirectionStub(rpc_channel)
        self._surfaces: dict[int, SurfaceClient] = {}
        self._emitters: dict[int, EmitterClient] = {}
        self._media: dict[int, MediumClient] = {}
        self._lock = threading.Lock()

    @functools.cached_property
    def layout(self) -> SceneLayout:
        """Film size and per-shape materials and emission (asked once)."""
        request = transport_pb2.SceneViewRequest(handle=self.handle)
        reply = self._call("SceneView.Layout", self._scene.Layout, request)
        return SceneLayout(
            width=reply.width,
            height=reply.height,
            material_handles=np.array(reply.material_handles, dtype=np.uint64),
            emits=np.array(reply.emits, dtype=bool),
            shape_emitters=np.array(reply.shape_emitters, dtype=np.uint32),
            primitive_counts=np.array(reply.primitive_counts, dtype=np.uint32),
            media_boundaries=np.array(reply.media_boundaries, dtype=bool),
            interior_media=np.array(reply.interior_media, dtype=np.uint32),
            exterior_media=np.array(reply.exterior_media, dtype=np.uint32),
            has_lights=reply.has_lights,
            has_environment=reply.has_environment,
            light_count=reply.light_count,
            emitter_handles=np.array(reply.emitter_handles, dtype=np.uint64),
            medium_handles=np.array(reply.medium_handles, dtype=np.uint64),
            camera_medium=reply.camera_medium,
            camera_has_lens=reply.camera_has_lens,
            camera_unreachable_reason=reply.camera_unreachable_reason,
        )

    def _rays(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        tnear: np.ndarray | float | None,
        tfar: np.ndarray | float | None,
        times: np.ndarray | float | None,
    ) -> geometry_pb2.IntersectRequest:
        """The Intersect request of a ray query on this scene."""
        return geometry_pb2.IntersectRequest(
            handle=self.handle, rays=ray_batch(origins, directions, tnear, tfar, times)
        )

    def intersect(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        tnear: np.ndarray | float | None = None,
        tfar: np.ndarray | float | None = None,
        times: np.ndarray | float | None = None,
    ) -> Hits:
        """The closest hit of each ray within [tnear, tfar] (default [0, inf))."""
        request = self._rays(origins, directions, tnear, tfar, times)
        reply = self._call("Intersect.Intersect", self._intersect.Intersect, request)
        return _decoded(Hits, reply)

    def occluded(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        tnear: np.ndarray | float | None = None,
        tfar: np.ndarray | float | None = None,
        times: np.ndarray | float | None = None,
    ) -> np.ndarray:
        """[N] bool: whether anything lies on each ray within its interval."""
        request = self._rays(origins, directions, tnear, tfar, times)
        reply = self._call("Intersect.Occluded", self._intersect.Occluded, request)
        return array_to_numpy(reply.occluded) != 0

    def cross_section(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        tnear: np.ndarray | float | None = None,
        tfar: np.ndarray | float | None = None,
        times: np.ndarray | float | None = None,
    ) -> Crossings:
        """Every hit along each ray within its interval, nearest first."""
        request = self._rays(origins, directions, tnear, tfar, times)
        return _decoded(
            Crossings, self._call("Intersect.CrossSection", self._intersect.CrossSection, request)
        )

    def camera_rays(self, points: np.ndarray) -> Rays:
        """The camera's rays for points [N,5]: film x, y in [0,1), lens u, v, shutter u."""
        n = len(points)
        request = transport_pb2.CameraRaysRequest(
            handle=self.handle, points=float_array(points, n, 5)
        )
        reply = self._call("SceneView.CameraRays", self._scene.CameraRays, request)
        times = array_to_numpy(reply.times) if reply.HasField("times") else np.zeros(n, np.float32)
        return Rays(array_to_numpy(reply.origins), array_to_numpy(reply.directions), times)

    def sample_lights(self, uniform: np.ndarray, points: np.ndarray) -> LightSamples:
        """A light sample seen from each point [N,3]; uniform [N,3]: choice, then position."""
        n = len(points)
        request = transport_pb2.SampleLightsRequest(
            handle=self.handle,
            uniform=float_array(uniform, n, 3),
            points=float_array(points, n, 3),
        )
        reply = self._call("SceneView.SampleLights", self._scene.SampleLights, request)
        return _light_samples(reply)

    def light_points(self, lights: np.ndarray, points: np.ndarray) -> LightSamples:
        """Each light [N] (below ``layout.light_count``) gathered into one point as seen
        from points [N,3] (a mesh light's centroid, a sphere's point facing them), chosen
        with probability 1: for methods that want hard shadows."""
        n = len(points)
        request = transport_pb2.LightPointsRequest(
            handle=self.handle,
            lights=numpy_to_array(np.asarray(lights, dtype=np.uint32)),
            points=float_array(points, n, 3),
        )
        return _light_samples(self._call("SceneView.LightPoints", self._scene.LightPoints, request))

    def sample_light_points(self, uniform: np.ndarray) -> LightPoints:
        """Points on the lights for paths that start there; uniform [N,3]: the light's
        choice (as ``sample_lights`` chooses), then a point uniform in its area."""
        request = transport_pb2.SampleLightPointsRequest(
            handle=self.handle, uniform=float_array(uniform, len(uniform), 3)
        )
        reply = self._call("SceneView.SampleLightPoints", self._scene.SampleLightPoints, request)
        return _decoded(LightPoints, reply)

    def light_pdf_area(self, shape_ids: np.ndarray) -> np.ndarray:
        """[N]: the area density ``sample_light_points`` has on each shape."""
        request = transport_pb2.LightPdfAreaRequest(
            handle=self.handle, shape_ids=numpy_to_array(np.asarray(shape_ids, dtype=np.uint32))
        )
        return array_to_numpy(
            self._call("SceneView.LightPdfArea", self._scene.LightPdfArea, request).pdf
        )

    def infinite_light_origins(
        self, directions: np.ndarray, uniform: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Where paths from a light at infinity travelling along directions [N,3] start
        (a point of the disk of the scene's bounding sphere, uniform [N,2]), and the
        disk's area density [N]."""
        n = len(directions)
        request = transport_pb2.InfiniteLightOriginsRequest(
            handle=self.handle,
            directions=float_array(directions, n, 3),
            uniform=float_array(uniform, n, 2),
        )
        reply = self._call(
            "SceneView.InfiniteLightOrigins", self._scene.InfiniteLightOrigins, request
        )
        return array_to_numpy(reply.origins), array_to_numpy(reply.pdf)

    def shutter_times(self, uniform: np.ndarray) -> np.ndarray:
        """[N]: the times in the shutter interval for primary coordinates uniform [N]."""
        request = transport_pb2.ShutterTimesRequest(
            handle=self.handle, uniform=float_array(uniform, len(uniform))
        )
        return array_to_numpy(
            self._call("SceneView.ShutterTimes", self._scene.ShutterTimes, request).times
        )

    def connect_to_camera(self, points: np.ndarray, lens: np.ndarray) -> CameraConnections:
        """Where points [N,3] appear on the film, seen through lens positions [N,2] in
        [0,1)² (primary coordinates 2, 3), and the camera's importance there."""
        n = len(points)
        request = transport_pb2.ConnectToCameraRequest(
            handle=self.handle, points=float_array(points, n, 3), lens=float_array(lens, n, 2)
        )
        reply = self._call("SceneView.ConnectToCamera", self._scene.ConnectToCamera, request)
        connections = _decoded(CameraConnections, reply)
        return connections._replace(connected=connections.connected != 0)

    def camera_direction_pdf(self, directions: np.ndarray) -> np.ndarray:
        """[N]: the density per solid angle of camera rays along directions [N,3]."""
        request = transport_pb2.CameraDirectionPdfRequest(
            handle=self.handle, directions=float_array(directions, len(directions), 3)
        )
        return array_to_numpy(
            self._call("SceneView.CameraDirectionPdf", self._scene.CameraDirectionPdf, request).pdf
        )

    def sample_spacing(
        self, points: np.ndarray, normals: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """dp/dx and dp/dy [N,3]: how far one film sample's step moves points [N,3] on
        surfaces with normals [N,3], seen from the camera (texture footprints)."""
        n = len(points)
        request = transport_pb2.SampleSpacingRequest(
            handle=self.handle, points=float_array(points, n, 3), normals=float_array(normals, n, 3)
        )
        reply = self._call("SceneView.SampleSpacing", self._scene.SampleSpacing, request)
        return array_to_numpy(reply.dpdx), array_to_numpy(reply.dpdy)

    def triangles(self, shape: int) -> np.ndarray:
        """[P,3,3]: the corners of shape ``shape``'s triangles in world space; empty for
        a shape that is not a mesh."""
        request = transport_pb2.TrianglesRequest(handle=self.handle, shape=shape)
        reply = self._call("SceneView.Triangles", self._scene.Triangles, request)
        return array_to_numpy(reply.corners).reshape(-1, 3, 3)

    def emission_async(self, rays: Rays, hits: Hits) -> Pending[tuple[np.ndarray, np.ndarray]]:
        """``emission`` sent now, its reply awaited by ``result()``."""
        n = len(rays.origins)
        request = transport_pb2.EmissionRequest(
            handle=self.handle,
            rays=ray_batch(rays.origins, rays.directions, times=rays.times),
            hits=geometry_pb2.IntersectReply(
                t=float_array(hits.t, n),
                normals=float_array(hits.normals, n, 3),
                uv=float_array(hits.uv, n, 2),
                shape_ids=numpy_to_array(np.asarray(hits.shape_ids, dtype=np.uint32)),
                primitive_ids=numpy_to_array(np.asarray(hits.primitive_ids, dtype=np.uint32)),
            ),
        )
        return self._call.start("SceneView.Emission", self._scene.Emission, request, _emitted)

    def emission(self, rays: Rays, hits: Hits) -> tuple[np.ndarray, np.ndarray]:
        """Radiance [N,3] emitted at the hits toward the rays' origins (zero for misses
        and shapes that do not emit), and the solid-angle density [N] with which
        ``sample_lights`` from the rays' origins would have chosen those points."""
        return self.emission_async(rays, hits).result()

    def shape_bounds(self, shape: int) -> tuple[np.ndarray, np.ndarray]:
        """The lower and upper corners [3] of the box around shape ``shape``."""
        request = geometry_pb2.ShapeRequest(handle=self.handle, shape=shape)
        reply = self._call("Shape.Bounds", self._shape.Bounds, request)
        return (
            np.array([reply.lower.x, reply.lower.y, reply.lower.z], np.float32),
            np.array([reply.upper.x, reply.upper.y, reply.upper.z], np.float32),
        )

    def shape_area(self, shape: int) -> float:
        """The surface area of shape ``shape``."""
        request = geometry_pb2.ShapeRequest(handle=self.handle, shape=shape)
        return self._call("Shape.Area", self._shape.Area, request).area

    def sample_surface_area(self, shape: int, uniform: np.ndarray) -> SurfaceSamples:
        """Points of shape ``shape`` uniform in area; uniform [N,3]: the primitive's
        choice, then the point on it."""
        request = geometry_pb2.SurfaceSampleRequest(
            handle=self.handle, shape=shape, uniform=float_array(uniform, len(uniform), 3)
        )
        reply = self._call("SampleSurfaceArea.Sample", self._by_area.Sample, request)
        return _decoded(SurfaceSamples, reply)

    def sample_surface_direction(
        self, shape: int, uniform: np.ndarray, points: np.ndarray
    ) -> SurfaceSamples:
        """Points of shape ``shape`` as seen from points [N,3], with densities per solid
        angle there (a sphere by its cone, large triangles by their solid angle when the
        job samples them so): the kernel's own light sampling."""
        n = len(points)
        request = geometry_pb2.SurfaceSampleRequest(
            handle=self.handle,
            shape=shape,
            uniform=float_array(uniform, n, 3),
            reference_points=float_array(points, n, 3),
        )
        reply = self._call("SampleSurfaceDirection.Sample", self._by_direction.Sample, request)
        return _decoded(SurfaceSamples, reply)

    def surface_direction_pdf(
        self, shape: int, points: np.ndarray, positions: np.ndarray, primitive_ids: np.ndarray
    ) -> np.ndarray:
        """[N] the density ``sample_surface_direction`` from points [N,3] has for the
        surface points (positions [N,3] on primitives [N]) the rays toward them meet."""
        n = len(points)
        request = geometry_pb2.SurfacePdfRequest(
            handle=self.handle,
            shape=shape,
            reference_points=float_array(points, n, 3),
            positions=float_array(positions, n, 3),
            primitive_ids=numpy_to_array(np.asarray(primitive_ids, dtype=np.uint32)),
        )
        reply = self._call("SampleSurfaceDirection.Pdf", self._by_direction.Pdf, request)
        return array_to_numpy(reply.pdf)

    def surface(self, material_handle: int) -> SurfaceClient:
        """The SurfaceModel of a material (``layout.material_handles[shape]``) on yarfd."""
        handle = int(material_handle)
        with self._lock:
            found = self._surfaces.get(handle)
            if found is None:
                found = self._surfaces[handle] = SurfaceClient(self._call, handle)
            return found

    def emitter(self, index: int) -> EmitterClient:
        """The Emitter of light replies' and ``layout.shape_emitters``' index ``index``."""
        handle = int(self.layout.emitter_handles[int(index)])
        with self._lock:
            found = self._emitters.get(handle)
            if found is None:
                found = self._emitters[handle] = EmitterClient(self._call, handle)
            return found

    def medium(self, index: int) -> MediumClient:
        """The Medium of ``layout``'s medium index ``index`` (interior_media,
        exterior_media, camera_medium)."""
        handle = int(self.layout.medium_handles[int(index)])
        with self._lock:
            found = self._media.get(handle)
            if found is None:
                found = self._media[handle] = MediumClient(self._call, handle)
            return found
