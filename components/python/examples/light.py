"""py_light: a light tracer, as a Python Transport written against yarfd's SceneView.

Paths start at the lights and every vertex is connected to the camera; each
connection splats where the vertex appears on the film (Dutré et al.; Veach
§10.2), as yarfd's C++ ``light`` does. Surfaces scatter importance. A vertex next
to the camera that is specular (a mirror seen directly) is never connected,
as in every light tracer. An environment seen directly is added by a camera
ray per point, as the C++ light tracer adds it. Participating media are not
handled: a scene with media is refused.

Each step is one batch: SampleLightPoints for the starts, one Emitter call per
light for the emission directions and radiance, then per bounce one
Intersect, one ConnectToCamera, one Occluded and per material one Evaluate
and one Sample (importance). No Russian roulette: paths end at ``max_depth``.

The local shading frame at a hit has +z the geometric normal (as py_path).

Primary sample space: 0-1 film (only for an environment seen directly), 2-3
lens, 4 shutter, 5 unused; then 6-7 the light's point, 8-9 the emission
direction, 10 the light's choice, 11 unused; from 12 on, 4 per scattering
bounce: the BSDF direction pair, the lobe choice, one unused.

Property: max_depth (int, default 5): the longest path in segments, counting
the one to the camera; 1 sees the lights only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from yarf_component import (
    AT_INFINITY,
    DELTA_DIRECTION,
    DELTA_POSITION,
    NONE,
    Frame,
    LightPoints,
    Rays,
    SceneView,
    Transport,
    TransportMode,
    normalize,
)
from yarf_component.rays import offset_origins, shadow_rays
from yarf_component.transport import FIRST_FREE, LENS, TIME

LIGHT_POSITION, EMISSION, LIGHT_CHOICE = FIRST_FREE, FIRST_FREE + 2, FIRST_FREE + 4
FIRST_BOUNCE, PER_BOUNCE = FIRST_FREE + 6, 4


@dataclass
class Splats:
    """Film contributions gathered over a batch: rows (x, y, r, g, b) and their points."""

    rows: list[np.ndarray]
    points: list[np.ndarray]

    def add(self, raster: np.ndarray, value: np.ndarray, points: np.ndarray) -> None:
        self.rows.append(np.concatenate([raster, value], axis=1).astype(np.float32))
        self.points.append(points.astype(np.uint32))

    def result(self) -> tuple[np.ndarray, bool, np.ndarray]:
        if not self.rows:
            return np.zeros((0, 5), np.float32), True, np.zeros(0, np.uint32)
        return np.concatenate(self.rows), True, np.concatenate(self.points)


def to_world(frames: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Local directions [N,3] in the frames [N,3,3] (rows s, t, n) as world directions."""
    return normalize(np.einsum("ni,nij->nj", w, frames).astype(np.float32))


class LightTracer(Transport):
    class_name = "py_light"
    summary = "Light tracer: paths from the lights connected to the camera, in Python"

    def __init__(self, max_depth: int = 5) -> None:
        if max_depth < 1:
            raise ValueError("property 'max_depth' must be ≥ 1")
        self.max_depth = max_depth

    def dimensions(self) -> int:
        return FIRST_BOUNCE + PER_BOUNCE * max(0, self.max_depth - 2)

    def prepare(self, scene: SceneView) -> None:
        layout = scene.layout
        if layout.camera_unreachable_reason:
            raise ValueError(f"py_light cannot render: {layout.camera_unreachable_reason}")
        if len(layout.medium_handles):
            raise ValueError(
                f"py_light ignores participating media; the scene has {len(layout.medium_handles)}"
            )

    def evaluate(self, scene: SceneView, points: np.ndarray) -> tuple[np.ndarray, bool, np.ndarray]:
        splats = Splats([], [])
        layout = scene.layout
        times = scene.shutter_times(points[:, TIME])
        if layout.has_environment:
            self._see_environment(scene, points, splats)
        if layout.has_lights:
            self._trace(scene, points, times, splats)
        return splats.result()

    def _trace(
        self, scene: SceneView, points: np.ndarray, times: np.ndarray, splats: Splats
    ) -> None:
        u = points
        starts = scene.sample_light_points(
            np.stack([u[:, LIGHT_CHOICE], u[:, LIGHT_POSITION], u[:, LIGHT_POSITION + 1]], 1)
        )
        valid = (starts.pdf > 0) & (starts.emitters != NONE)
        surface = valid & ((starts.flags & (DELTA_POSITION | AT_INFINITY)) == 0)
        self._connect_lights(scene, points, times, starts, np.flatnonzero(surface), splats)
        if self.max_depth < 2:
            return
        n = len(points)
        directions = np.zeros((n, 3), np.float32)
        beta = np.zeros((n, 3), np.float32)
        origins = starts.positions.copy()
        for emitter in np.unique(starts.emitters[valid]):
            rows = np.flatnonzero(valid & (starts.emitters == emitter))
            client = scene.emitter(int(emitter))
            along_axis = (starts.flags[rows] & DELTA_DIRECTION) != 0
            w, pdf = client.sample_direction(u[rows, EMISSION : EMISSION + 2])
            w[along_axis] = (0, 0, 1)
            pdf[along_axis] = 1
            radiance = client.radiance(w, starts.uv[rows])
            world = to_world(starts.frames[rows], w)
            density = starts.pdf[rows] * pdf
            infinite = (starts.flags[rows] & AT_INFINITY) != 0
            if infinite.any():
                at = rows[infinite]
                disk, pdf_area = scene.infinite_light_origins(
                    world[infinite], u[at, LIGHT_POSITION : LIGHT_POSITION + 2]
                )
                origins[at] = disk
                density[infinite] *= pdf_area
            delta = (starts.flags[rows] & DELTA_POSITION) != 0
            cos = np.where(
                delta | infinite, 1, np.abs(np.sum(starts.normals[rows] * world, axis=1))
            )
            ok = density > 0
            beta[rows[ok]] = radiance[ok] * (cos[ok] / density[ok])[:, None]
            directions[rows] = world
            leaves_surface = ~(delta | infinite)
            moved = rows[leaves_surface]
            origins[moved] = offset_origins(
                starts.positions[moved], starts.normals[moved], world[leaves_surface]
            )
        alive = np.flatnonzero(valid & (beta.max(axis=1) > 0))
        origins, directions, beta = origins[alive], directions[alive], beta[alive]
        for bounce in range(1, self.max_depth):
            if alive.size == 0:
                return
            alive, origins, directions, beta = self._bounce(
                scene, points, times, bounce, alive, origins, directions, beta, splats
            )

    @staticmethod
    def _connect_lights(
        scene: SceneView,
        points: np.ndarray,
        times: np.ndarray,
        starts: LightPoints,
        rows: np.ndarray,
        splats: Splats,
    ) -> None:
        """Paths of one segment: points on surface lights the camera sees."""
        if rows.size == 0:
            return
        positions = starts.positions[rows]
        normals = starts.normals[rows]
        seen = scene.connect_to_camera(positions, points[rows, LENS : LENS + 2])
        c = np.flatnonzero(seen.connected)
        if c.size == 0:
            return
        rows, positions, normals = rows[c], positions[c], normals[c]
        lens = seen.lens_points[c]
        d = lens - positions
        w = starts.frames[rows] @ normalize(d)[:, :, None]
        w = w[:, :, 0]
        radiance = np.zeros((len(rows), 3), np.float32)
        for emitter in np.unique(starts.emitters[rows]):
            group = starts.emitters[rows] == emitter
            radiance[group] = scene.emitter(int(emitter)).radiance(w[group], starts.uv[rows[group]])
        scale = np.abs(w[:, 2]) * seen.importance[c] / (np.sum(d * d, axis=1) * starts.pdf[rows])
        value = radiance * scale[:, None]
        LightTracer._splat_unoccluded(
            scene, positions, normals, lens, times[rows], seen.raster[c], value, rows, splats
        )

    @staticmethod
    def _splat_unoccluded(
        scene: SceneView,
        positions: np.ndarray,
        normals: np.ndarray,
        lens: np.ndarray,
        times: np.ndarray,
        raster: np.ndarray,
        value: np.ndarray,
        owners: np.ndarray,
        splats: Splats,
    ) -> None:
        live = value.max(axis=1) > 0
        if not live.any():
            return
        origins, directions, tfar = shadow_rays(positions[live], normals[live], lens[live])
        blocked = scene.occluded(origins, directions, tfar=tfar, times=times[live])
        clear = np.flatnonzero(live)[~blocked]
        splats.add(raster[clear], value[clear], owners[clear])

    def _bounce(
        self,
        scene: SceneView,
        points: np.ndarray,
        times: np.ndarray,
        bounce: int,
        alive: np.ndarray,
        origins: np.ndarray,
        directions: np.ndarray,
        beta: np.ndarray,
        splats: Splats,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The hits of the paths after `bounce` segments: connected to the camera, then
        scattered on while the next vertex may still reach it."""
        hits = scene.intersect(origins, directions, times=times[alive])
        v = np.flatnonzero(hits.found)
        paths, beta = alive[v], beta[v]
        positions = origins[v] + directions[v] * hits.t[v][:, None]
        normals = hits.normals[v]
        frames = Frame(normals)
        wi = frames.to_local(-directions[v])
        uv = hits.uv[v]
        handles = scene.layout.material_handles[hits.shape_ids[v].astype(np.int64)]
        materials, material = np.unique(handles, return_inverse=True)
        material = material.reshape(-1)
        surfaces = [scene.surface(int(h)) for h in materials]

        # Every vertex to the camera.
        seen = scene.connect_to_camera(positions, points[paths, LENS : LENS + 2])
        c = np.flatnonzero(seen.connected)
        if c.size:
            lens = seen.lens_points[c]
            d = lens - positions[c]
            wo = Frame(normals[c]).to_local(normalize(d))
            f = np.zeros((len(c), 3), np.float32)
            for index, surface in enumerate(surfaces):
                group = material[c] == index
                if group.any():
                    f[group] = surface.evaluate(
                        wi[c][group], wo[group], uv[c][group], TransportMode.IMPORTANCE
                    )
            scale = np.abs(wo[:, 2]) * seen.importance[c] / np.sum(d * d, axis=1)
            value = beta[c] * f * scale[:, None]
            self._splat_unoccluded(
                scene,
                positions[c],
                normals[c],
                lens,
                times[paths[c]],
                seen.raster[c],
                value,
                paths[c],
                splats,
            )

        # Scatter importance onward.
        if bounce + 2 > self.max_depth:
            empty = np.zeros((0, 3), np.float32)
            return paths[:0], empty, empty, empty
        base = FIRST_BOUNCE + PER_BOUNCE * (bounce - 1)
        u = points[paths, base : base + PER_BOUNCE]
        uniform = np.stack([u[:, 2], u[:, 0], u[:, 1]], axis=1)
        m = len(paths)
        wo = np.zeros((m, 3), np.float32)
        weight = np.zeros((m, 3), np.float32)
        pdf = np.zeros(m, np.float32)
        pending = [
            (
                rows,
                surface.sample_async(
                    wi[rows], uv[rows], uniform[rows], 0, TransportMode.IMPORTANCE
                ),
            )
            for index, surface in enumerate(surfaces)
            for rows in [np.flatnonzero(material == index)]
        ]
        for rows, call in pending:
            wo[rows], weight[rows], pdf[rows], _ = call.result()
        go_on = (pdf > 0) & (weight.max(axis=1) > 0)
        onward = normalize(frames.to_world(wo)[go_on])
        next_origins = offset_origins(positions[go_on], normals[go_on], onward)
        return paths[go_on], next_origins, onward, (beta * weight)[go_on]

    @staticmethod
    def _see_environment(scene: SceneView, points: np.ndarray, splats: Splats) -> None:
        """Paths of one segment from an environment: a camera ray per point splats what
        it sees of the environment where it lands (one pass of W×H points puts one such
        ray in each pixel on average)."""
        rays = scene.camera_rays(points[:, :5])
        hits = scene.intersect(rays.origins, rays.directions, times=rays.times)
        miss = np.flatnonzero(~hits.found)
        if miss.size == 0:
            return
        radiance, _ = scene.emission(
            Rays(rays.origins[miss], rays.directions[miss], rays.times[miss]), hits.take(miss)
        )
        layout = scene.layout
        raster = np.stack([points[miss, 0] * layout.width, points[miss, 1] * layout.height], axis=1)
        splats.add(raster, radiance, miss)
