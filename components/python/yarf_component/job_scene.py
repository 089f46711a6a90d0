"""The scene of a running job, for transports: yarfd's JobScene, Intersect,
Shape, SampleSurfaceArea, SampleSurfaceDirection and SurfaceModel services as
numpy calls.

A Transport's ``prepare`` and ``evaluate`` receive a JobScene bound to the
yarfd that called them and to the job's scene handle. Arrays are float32,
one row per ray or point, world space; failures raise JobSceneError naming
the call. Materials are SurfaceClients (job_surface.py).
"""

from __future__ import annotations

import functools
import threading
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from yarf.client import array_to_numpy, numpy_to_array
from yarf.v1 import geometry_pb2, geometry_pb2_grpc, transport_pb2, transport_pb2_grpc
from yarf_component.channels import channel
from yarf_component.job_calls import Caller, Pending, float_array, ray_batch
from yarf_component.job_surface import SurfaceClient

# shape_ids of a ray that hit nothing.
MISS = 0xFFFFFFFF
# Deadline of each call, seconds.
DEFAULT_TIMEOUT = 60.0


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


class LightSamples(NamedTuple):
    """Next-event estimation: unit directions [N,3] toward the light samples, their
    distances [N], the unoccluded radiance arriving [N,3], the solid-angle pdf [N]
    (0: nothing sampled) and delta [N] bool (point lights: no MIS)."""

    directions: np.ndarray
    distances: np.ndarray
    radiance: np.ndarray
    pdf: np.ndarray
    delta: np.ndarray


class SurfaceSamples(NamedTuple):
    """Points sampled on a shape: positions [N,3], unit normals [N,3] on the side the
    shape's normals face, densities [N] (per unit area, or per solid angle at the
    reference points; 0: nothing sampled), uv [N,2] and primitive_ids [N]."""

    positions: np.ndarray
    normals: np.ndarray
    pdf: np.ndarray
    uv: np.ndarray
    primitive_ids: np.ndarray


def _surface_samples(reply: geometry_pb2.SurfaceSampleReply) -> SurfaceSamples:
    return SurfaceSamples(
        positions=array_to_numpy(reply.positions),
        normals=array_to_numpy(reply.normals),
        pdf=array_to_numpy(reply.pdf),
        uv=array_to_numpy(reply.uv),
        primitive_ids=array_to_numpy(reply.primitive_ids),
    )


@dataclass(frozen=True)
class SceneLayout:
    """The film size, and per shape its material's SurfaceModel handle and whether it emits."""

    width: int
    height: int
    material_handles: np.ndarray
    emits: np.ndarray
    has_lights: bool


def _emitted(reply: transport_pb2.EmissionReply) -> tuple[np.ndarray, np.ndarray]:
    return array_to_numpy(reply.radiance), array_to_numpy(reply.pdf)


class JobScene:
    """Scene ``handle`` of a job on the yarfd at ``address``."""

    def __init__(self, address: str, handle: int, *, timeout: float = DEFAULT_TIMEOUT) -> None:
        self.address = address
        self.handle = handle
        self._call = Caller(address, timeout)
        rpc_channel = channel(address)
        self._scene = transport_pb2_grpc.JobSceneStub(rpc_channel)
        self._intersect = geometry_pb2_grpc.IntersectStub(rpc_channel)
        self._shape = geometry_pb2_grpc.ShapeStub(rpc_channel)
        self._by_area = geometry_pb2_grpc.SampleSurfaceAreaStub(rpc_channel)
        self._by_direction = geometry_pb2_grpc.SampleSurfaceDirectionStub(rpc_channel)
        self._surfaces: dict[int, SurfaceClient] = {}
        self._lock = threading.Lock()

    @functools.cached_property
    def layout(self) -> SceneLayout:
        """Film size and per-shape materials and emission (asked once)."""
        request = transport_pb2.JobSceneRequest(handle=self.handle)
        reply = self._call("JobScene.Layout", self._scene.Layout, request)
        return SceneLayout(
            width=reply.width,
            height=reply.height,
            material_handles=np.array(reply.material_handles, dtype=np.uint64),
            emits=np.array(reply.emits, dtype=bool),
            has_lights=reply.has_lights,
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
        request = geometry_pb2.IntersectRequest(
            handle=self.handle, rays=ray_batch(origins, directions, tnear, tfar, times)
        )
        reply = self._call("Intersect.Intersect", self._intersect.Intersect, request)
        return Hits(
            t=array_to_numpy(reply.t),
            normals=array_to_numpy(reply.normals),
            uv=array_to_numpy(reply.uv),
            shape_ids=array_to_numpy(reply.shape_ids),
            primitive_ids=array_to_numpy(reply.primitive_ids),
        )

    def occluded(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        tnear: np.ndarray | float | None = None,
        tfar: np.ndarray | float | None = None,
        times: np.ndarray | float | None = None,
    ) -> np.ndarray:
        """[N] bool: whether anything lies on each ray within its interval."""
        request = geometry_pb2.IntersectRequest(
            handle=self.handle, rays=ray_batch(origins, directions, tnear, tfar, times)
        )
        reply = self._call("Intersect.Occluded", self._intersect.Occluded, request)
        return array_to_numpy(reply.occluded) != 0

    def camera_rays(self, points: np.ndarray) -> Rays:
        """The camera's rays for points [N,5]: film x, y in [0,1), lens u, v, shutter u."""
        n = len(points)
        request = transport_pb2.CameraRaysRequest(
            handle=self.handle, points=float_array(points, n, 5)
        )
        reply = self._call("JobScene.CameraRays", self._scene.CameraRays, request)
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
        reply = self._call("JobScene.SampleLights", self._scene.SampleLights, request)
        return LightSamples(
            directions=array_to_numpy(reply.directions),
            distances=array_to_numpy(reply.distances),
            radiance=array_to_numpy(reply.radiance),
            pdf=array_to_numpy(reply.pdf),
            delta=array_to_numpy(reply.delta) != 0,
        )

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
        return self._call.start("JobScene.Emission", self._scene.Emission, request, _emitted)

    def emission(self, rays: Rays, hits: Hits) -> tuple[np.ndarray, np.ndarray]:
        """Radiance [N,3] emitted at the hits toward the rays' origins (zero for misses
        and shapes that do not emit), and the solid-angle density [N] with which
        ``sample_lights`` from the rays' origins would have chosen those points."""
        return self.emission_async(rays, hits).result()

    def splat(self, contributions: np.ndarray) -> None:
        """Adds contributions [M,5] (raster x, y in pixels, RGB) to the film, summed."""
        request = transport_pb2.SplatRequest(
            handle=self.handle, contributions=float_array(contributions, len(contributions), 5)
        )
        self._call("JobScene.Splat", self._scene.Splat, request)

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
        return _surface_samples(reply)

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
        return _surface_samples(reply)

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
