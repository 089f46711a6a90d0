"""py_direct: direct lighting from the emitting shapes, sampled through yarfd's
SampleSurfaceDirection service, as a Python Transport.

Each camera sample sees what its ray hits emit, and at that hit gathers the
light of the emitting shapes by two strategies weighed by the power
heuristic: a point of one emitting shape, the shape chosen uniformly and
the point drawn by SampleSurfaceDirection from the hit (a sphere by the
cone it subtends, a triangle that subtends a fair solid angle by that
angle, anything else by area), and a BSDF sample whose ray may meet an
emitting shape, weighed by SampleSurfaceDirection.Pdf. Point, spot and
infinite lights are not seen: only shapes. The expectation is that of a
path tracer's paths of at most two segments (``path`` with max_depth 2)
in a scene whose only lights are emitting shapes.

Primary sample space: 0-4 the camera, 5 unused, then
    6, 7  BSDF direction     8, 9  point on the light
    10    light choice       11    BSDF lobe

Calls per batch: CameraRays, Intersect, Emission (three times), per
emitting shape SampleSurfaceDirection.Sample and .Pdf, per material
Evaluate, Pdf and Sample, and Occluded.
"""

from __future__ import annotations

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

BSDF_DIRECTION, LIGHT_POSITION, LIGHT_CHOICE, BSDF_LOBE = (FIRST_FREE + k for k in (0, 2, 4, 5))


class DirectLighting(Transport):
    class_name = "py_direct"
    summary = (
        "Direct light from emitting shapes sampled by SampleSurfaceDirection, with MIS, in Python"
    )

    def dimensions(self) -> int:
        return BSDF_LOBE + 1

    def evaluate(self, scene: SceneView, points: np.ndarray) -> tuple[np.ndarray, bool]:
        layout = scene.layout
        rays = scene.camera_rays(points[:, :5])
        hits = scene.intersect(rays.origins, rays.directions, times=rays.times)
        radiance, _ = scene.emission(rays, hits)
        lights = np.flatnonzero(layout.emits)
        found = np.flatnonzero(hits.found)
        if lights.size and found.size:
            radiance[found] += self._direct(scene, points[found], rays, hits.take(found), found)
        film = np.stack([points[:, 0] * layout.width, points[:, 1] * layout.height], axis=1)
        return np.concatenate([film, radiance], axis=1), False

    def _direct(
        self, scene: SceneView, u: np.ndarray, rays: Rays, hits: Hits, rows: np.ndarray
    ) -> np.ndarray:
        """The light the hits (rows of the camera batch) receive from the emitting shapes."""
        directions = rays.directions[rows]
        positions = rays.origins[rows] + directions * hits.t[:, None]
        times = None if rays.times is None else rays.times[rows]
        normals = hits.normals
        wi = Frame(normals).to_local(-directions)
        handles = scene.layout.material_handles[hits.shape_ids.astype(np.int64)]
        unique, material = np.unique(handles, return_inverse=True)
        material = material.reshape(-1)
        surfaces = [scene.surface(int(h)) for h in unique]
        total = np.zeros((len(rows), 3), np.float32)
        for index, surface in enumerate(surfaces):
            group = np.flatnonzero(material == index)
            at = _Vertices(positions[group], normals[group], wi[group], hits.uv[group], u[group])
            at_times = None if times is None else times[group]
            if samples_lights(surface.lobes()):
                total[group] += _light_sample(scene, surface, at, at_times)
            total[group] += _bsdf_sample(scene, surface, at, at_times)
        return total


@dataclass
class _Vertices:
    """Camera hits of one material: positions, geometric normals, wi in their frames,
    uv, and the rows of primary sample space."""

    positions: np.ndarray
    normals: np.ndarray
    wi: np.ndarray
    uv: np.ndarray
    u: np.ndarray


def _chosen_lights(scene: SceneView, u_choice: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The emitting shape each u picks uniformly, and u rescaled within its share."""
    lights = np.flatnonzero(scene.layout.emits)
    scaled = u_choice * len(lights)
    pick = np.minimum(scaled.astype(np.int64), len(lights) - 1)
    rest = np.clip(scaled - pick, 0, np.nextafter(np.float32(1), np.float32(0))).astype(np.float32)
    return lights[pick], rest


def _light_pdf(
    scene: SceneView,
    shapes: np.ndarray,
    origins: np.ndarray,
    positions: np.ndarray,
    primitives: np.ndarray,
) -> np.ndarray:
    """Density per solid angle with which _light_sample finds each surface point."""
    count = int(scene.layout.emits.sum())
    pdf = np.zeros(len(shapes), np.float32)
    for shape in np.unique(shapes):
        rows = np.flatnonzero(shapes == shape)
        pdf[rows] = scene.surface_direction_pdf(
            int(shape), origins[rows], positions[rows], primitives[rows]
        )
    return pdf / count


def _emitted(
    scene: SceneView,
    origins: np.ndarray,
    targets: np.ndarray,
    normals: np.ndarray,
    uv: np.ndarray,
    shapes: np.ndarray,
    primitives: np.ndarray,
) -> np.ndarray:
    """Radiance the surface points send back toward the origins."""
    span = targets - origins
    distance = np.linalg.norm(span, axis=1).astype(np.float32)
    hits = Hits(
        t=distance,
        normals=normals,
        uv=uv,
        shape_ids=shapes.astype(np.uint32),
        primitive_ids=primitives.astype(np.uint32),
    )
    directions = (span / np.maximum(distance, np.float32(1e-30))[:, None]).astype(np.float32)
    return scene.emission(Rays(origins, directions), hits)[0]


def _light_sample(
    scene: SceneView, surface: SurfaceClient, at: _Vertices, times: np.ndarray | None
) -> np.ndarray:
    """One point of a light by SampleSurfaceDirection, weighed against BSDF sampling."""
    shapes, rest = _chosen_lights(scene, at.u[:, LIGHT_CHOICE])
    n = len(shapes)
    uniform = np.stack([rest, at.u[:, LIGHT_POSITION], at.u[:, LIGHT_POSITION + 1]], axis=1).astype(
        np.float32
    )
    positions = np.zeros((n, 3), np.float32)
    normals = np.zeros((n, 3), np.float32)
    uv = np.zeros((n, 2), np.float32)
    primitives = np.zeros(n, np.uint32)
    pdf = np.zeros(n, np.float32)
    for shape in np.unique(shapes):
        rows = np.flatnonzero(shapes == shape)
        s = scene.sample_surface_direction(int(shape), uniform[rows], at.positions[rows])
        positions[rows], normals[rows], uv[rows] = s.positions, s.normals, s.uv
        primitives[rows], pdf[rows] = s.primitive_ids, s.pdf
    pdf /= int(scene.layout.emits.sum())
    radiance = _emitted(scene, at.positions, positions, normals, uv, shapes, primitives)
    directions = normalize(positions - at.positions)
    wo = Frame(at.normals).to_local(directions)
    f = surface.evaluate(at.wi, wo, at.uv)
    bsdf_pdf = surface.pdf(at.wi, wo, at.uv)
    sampled = pdf > 0
    weight = power_heuristic(pdf, bsdf_pdf) * np.abs(wo[:, 2]) / np.where(sampled, pdf, 1)
    contribution = f * radiance * weight[:, None]
    live = np.flatnonzero(sampled & (contribution.max(axis=1) > 0))
    out = np.zeros((n, 3), np.float32)
    if live.size:
        origins, rays, tfar = shadow_rays(at.positions[live], at.normals[live], positions[live])
        blocked = scene.occluded(
            origins, rays, tfar=tfar, times=None if times is None else times[live]
        )
        clear = live[~blocked]
        out[clear] = contribution[clear]
    return out


def _bsdf_sample(
    scene: SceneView, surface: SurfaceClient, at: _Vertices, times: np.ndarray | None
) -> np.ndarray:
    """One BSDF sample; the emitting shape its ray meets, weighed against light sampling."""
    uniform = np.stack(
        [at.u[:, BSDF_LOBE], at.u[:, BSDF_DIRECTION], at.u[:, BSDF_DIRECTION + 1]], axis=1
    ).astype(np.float32)
    wo, weight, bsdf_pdf, flags = surface.sample(at.wi, at.uv, uniform)
    out = np.zeros((len(wo), 3), np.float32)
    go = np.flatnonzero((bsdf_pdf > 0) & (weight.max(axis=1) > 0))
    if not go.size:
        return out
    onward = normalize(Frame(at.normals[go]).to_world(wo[go]))
    origins = offset_origins(at.positions[go], at.normals[go], onward)
    hits = scene.intersect(origins, onward, times=None if times is None else times[go])
    emits = hits.found.copy()
    emits[emits] = scene.layout.emits[hits.shape_ids[emits].astype(np.int64)]
    e = np.flatnonzero(emits)
    if not e.size:
        return out
    rows = go[e]
    hit_positions = origins[e] + onward[e] * hits.t[e][:, None]
    radiance = _emitted(
        scene,
        origins[e],
        hit_positions,
        hits.normals[e],
        hits.uv[e],
        hits.shape_ids[e],
        hits.primitive_ids[e],
    )
    light_pdf = _light_pdf(
        scene, hits.shape_ids[e], at.positions[rows], hit_positions, hits.primitive_ids[e]
    )
    delta = (flags[rows] & ScatterFlags.DELTA) != 0
    lit = samples_lights(surface.lobes())
    mis = np.where(delta | (not lit), np.float32(1), power_heuristic(bsdf_pdf[rows], light_pdf))
    out[rows] = weight[rows] * radiance * mis[:, None]
    return out
