"""py_path: a path tracer with next-event estimation and MIS, as a Python Transport.

Paths start at the camera and advance together, one bounce at a time, each
bounce one batch: one Intersect for all live paths, one Emission for those
that hit an emitter, one SampleLights and one Occluded for the light
samples, and per material one Evaluate, one Pdf and one Sample call to
yarfd's SurfaceModel. Calls that do not wait for each other are in flight
together (the Emission, every material's Sample and, once the lights are
sampled, every Evaluate and Pdf), so a bounce costs four round trips
whatever the number of materials.

At every surface hit the path takes a light sample (next-event
estimation; skipped for purely specular materials) and a BSDF sample; an
emitter found by a BSDF sample is weighted against light sampling with
the power heuristic, one found by a camera ray or after a specular bounce
counts fully. No Russian roulette: paths end at ``max_depth``.

As yarfd's C++ ``path``, the local shading frame at a hit has +z the
geometric normal as the shape gives it (not flipped toward the ray), so
wi.z < 0 when the ray arrives from the back; two-sided models handle both.

Primary sample space: 0-4 the camera (film x, y, lens u, v, shutter), 5
unused, then 6 per scattering bounce k = 0, 1, ... from 6 + 6k, so that
every pair (2j, 2j+1) is one 2-D choice:
    +0, +1  BSDF direction       +2, +3  light position
    +4      light choice         +5      BSDF lobe
``dimensions()`` is 6 + 6·(max_depth - 1): the last segment does not scatter.

Property: max_depth (int, default 5): the longest path in segments, 1 shows
emitters only, 2 adds direct light.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from yarf_component import (
    Frame,
    Hits,
    Rays,
    ScatterFlags,
    SceneView,
    SurfaceClient,
    Transport,
    normalize,
    power_heuristic,
    samples_lights,
)
from yarf_component.rays import offset_origins, shadow_rays
from yarf_component.transport import FIRST_FREE

PER_BOUNCE = 6
BSDF_DIRECTION, LIGHT_POSITION, LIGHT_CHOICE, BSDF_LOBE = 0, 2, 4, 5


@dataclass
class Paths:
    """Per path of the batch: what it carries and what it has gathered."""

    throughput: np.ndarray
    radiance: np.ndarray
    # Density of the last BSDF sample, and whether an emitter hit next
    # counts fully (camera ray, specular bounce, no light sample).
    bsdf_pdf: np.ndarray
    full_weight: np.ndarray

    @classmethod
    def start(cls, n: int) -> Paths:
        return cls(
            throughput=np.ones((n, 3), np.float32),
            radiance=np.zeros((n, 3), np.float32),
            bsdf_pdf=np.zeros(n, np.float32),
            full_weight=np.ones(n, bool),
        )


@dataclass
class Vertices:
    """The surface hits of one bounce that scatter, with the path each belongs to."""

    paths: np.ndarray
    positions: np.ndarray
    normals: np.ndarray
    wi: np.ndarray
    uv: np.ndarray
    times: np.ndarray
    # This bounce's coordinates of each vertex's point, [M, 6].
    u: np.ndarray
    # Index into the bounce's materials.
    material: np.ndarray

    def take(self, rows: np.ndarray) -> Vertices:
        return Vertices(**{name: value[rows] for name, value in vars(self).items()})


class PathTracer(Transport):
    class_name = "py_path"
    summary = "Path tracer with next-event estimation and MIS, batched per bounce, in Python"
    # Camera samples only, each in its own pixel: the farm may tile its jobs.
    capabilities = ("pixel_local",)

    def __init__(self, max_depth: int = 5) -> None:
        if max_depth < 1:
            raise ValueError("property 'max_depth' must be ≥ 1")
        self.max_depth = max_depth

    def dimensions(self) -> int:
        return FIRST_FREE + PER_BOUNCE * (self.max_depth - 1)

    def evaluate(self, scene: SceneView, points: np.ndarray) -> tuple[np.ndarray, bool]:
        layout = scene.layout
        state = Paths.start(len(points))
        alive = np.arange(len(points))
        rays = scene.camera_rays(points[:, :5])
        for depth in range(1, self.max_depth + 1):
            hits = scene.intersect(rays.origins, rays.directions, times=rays.times)
            gather = self._start_emission(scene, state, alive, rays, hits)
            if depth < self.max_depth and hits.found.any():
                base = FIRST_FREE + PER_BOUNCE * (depth - 1)
                vertices, surfaces = self._vertices(scene, points, base, alive, rays, hits)
                rays, alive = self._scatter(scene, state, vertices, surfaces)
            else:
                alive = alive[:0]
            gather()
            if alive.size == 0:
                break
        film = np.stack([points[:, 0] * layout.width, points[:, 1] * layout.height], axis=1)
        return np.concatenate([film, state.radiance], axis=1), False

    @staticmethod
    def _start_emission(
        scene: SceneView, state: Paths, alive: np.ndarray, rays: Rays, hits: Hits
    ) -> Callable[[], None]:
        """Asks for the light of the emitters this bounce's rays hit; the function returned
        adds it, weighted against light sampling as the paths stood when asked."""
        emits = np.zeros(len(alive), bool)
        found = hits.found
        emits[found] = scene.layout.emits[hits.shape_ids[found].astype(np.int64)]
        if not emits.any():
            return lambda: None
        e = np.flatnonzero(emits)
        times = None if rays.times is None else rays.times[e]
        pending = scene.emission_async(
            Rays(rays.origins[e], rays.directions[e], times), hits.take(e)
        )
        owners = alive[e]
        throughput = state.throughput[owners]
        full_weight = state.full_weight[owners]
        bsdf_pdf = state.bsdf_pdf[owners]

        def gather() -> None:
            emitted, light_pdf = pending.result()
            weight = np.where(full_weight, np.float32(1), power_heuristic(bsdf_pdf, light_pdf))
            state.radiance[owners] += throughput * emitted * weight[:, None]

        return gather

    @staticmethod
    def _vertices(
        scene: SceneView, points: np.ndarray, base: int, alive: np.ndarray, rays: Rays, hits: Hits
    ) -> tuple[Vertices, list[SurfaceClient]]:
        """The hits as vertices in their local frames, and the bounce's materials."""
        v = np.flatnonzero(hits.found)
        directions = rays.directions[v]
        normals = hits.normals[v]
        handles = scene.layout.material_handles[hits.shape_ids[v].astype(np.int64)]
        unique, material = np.unique(handles, return_inverse=True)
        times = np.zeros(len(v), np.float32) if rays.times is None else rays.times[v]
        vertices = Vertices(
            paths=alive[v],
            positions=rays.origins[v] + directions * hits.t[v][:, None],
            normals=normals,
            wi=Frame(normals).to_local(-directions),
            uv=hits.uv[v],
            times=times,
            u=points[alive[v], base : base + PER_BOUNCE],
            material=material.reshape(-1),
        )
        return vertices, [scene.surface(int(h)) for h in unique]

    def _scatter(
        self, scene: SceneView, state: Paths, vertices: Vertices, surfaces: list[SurfaceClient]
    ) -> tuple[Rays, np.ndarray]:
        """Light and BSDF samples at the vertices; the rays of the paths that go on."""
        u = vertices.u
        uniform = np.stack([u[:, BSDF_LOBE], u[:, BSDF_DIRECTION], u[:, BSDF_DIRECTION + 1]], 1)
        groups = [np.flatnonzero(vertices.material == index) for index in range(len(surfaces))]
        sampling = [
            surface.sample_async(vertices.wi[rows], vertices.uv[rows], uniform[rows])
            for surface, rows in zip(surfaces, groups, strict=True)
        ]
        sample_lights = np.array(
            [scene.layout.has_lights and samples_lights(s.lobes()) for s in surfaces]
        )[vertices.material]
        if sample_lights.any():
            self._direct_light(scene, state, vertices.take(sample_lights), surfaces)

        m = len(vertices.paths)
        wo = np.zeros((m, 3), np.float32)
        weight = np.zeros((m, 3), np.float32)
        pdf = np.zeros(m, np.float32)
        flags = np.zeros(m, np.uint32)
        for rows, pending in zip(groups, sampling, strict=True):
            wo[rows], weight[rows], pdf[rows], flags[rows] = pending.result()
        go_on = (pdf > 0) & (weight.max(axis=1) > 0)
        next_paths = vertices.paths[go_on]
        state.throughput[next_paths] *= weight[go_on]
        state.bsdf_pdf[next_paths] = pdf[go_on]
        delta = (flags[go_on] & ScatterFlags.DELTA) != 0
        state.full_weight[next_paths] = ~sample_lights[go_on] | delta
        normals = vertices.normals[go_on]
        onward = normalize(Frame(normals).to_world(wo[go_on]))
        origins = offset_origins(vertices.positions[go_on], normals, onward)
        return Rays(origins, onward, vertices.times[go_on]), next_paths

    @staticmethod
    def _direct_light(
        scene: SceneView, state: Paths, vertices: Vertices, surfaces: list[SurfaceClient]
    ) -> None:
        """Next-event estimation: one light sample per vertex, MIS-weighted, if unoccluded."""
        u = vertices.u
        choice = np.stack([u[:, LIGHT_CHOICE], u[:, LIGHT_POSITION], u[:, LIGHT_POSITION + 1]], 1)
        light = scene.sample_lights(choice, vertices.positions)
        wo = Frame(vertices.normals).to_local(light.directions)
        wi, uv = vertices.wi, vertices.uv
        asked = [
            (
                rows,
                surfaces[index].evaluate_async(wi[rows], wo[rows], uv[rows]),
                surfaces[index].pdf_async(wi[rows], wo[rows], uv[rows]),
            )
            for index in np.unique(vertices.material)
            for rows in [np.flatnonzero(vertices.material == index)]
        ]
        f = np.zeros((len(u), 3), np.float32)
        pdf = np.zeros(len(u), np.float32)
        for rows, value, density in asked:
            f[rows] = value.result()
            pdf[rows] = density.result()
        sampled = light.pdf > 0
        mis = np.where(light.delta, np.float32(1), power_heuristic(light.pdf, pdf))
        scale = np.abs(wo[:, 2]) * mis / np.where(sampled, light.pdf, np.float32(1))
        owners = vertices.paths
        contribution = state.throughput[owners] * f * light.radiance * scale[:, None]
        live = sampled & (contribution.max(axis=1) > 0)
        if not live.any():
            return
        positions = vertices.positions[live]
        targets = positions + light.directions[live] * light.distances[live][:, None]
        origins, directions, tfar = shadow_rays(positions, vertices.normals[live], targets)
        # A point light has no surface to stop short of.
        tfar = np.where(light.delta[live], np.linalg.norm(targets - origins, axis=1), tfar)
        blocked = scene.occluded(origins, directions, tfar=tfar, times=vertices.times[live])
        clear = np.flatnonzero(live)[~blocked]
        state.radiance[owners[clear]] += contribution[clear]
