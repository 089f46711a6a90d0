"""py_ambient_occlusion: ambient occlusion, as a Python Transport.

Each point of primary sample space is one camera sample: the camera ray
from coordinates 0-4, and at its first hit one direction drawn from the
cosine-weighted hemisphere on the side the ray arrived from (coordinates 6
and 7). The sample is white times the direction's visibility within
``distance``: its mean is the ambient occlusion (1/π)∫ V(ω) cos θ dω.
Rays that hit nothing give black.

Property: distance (float, scene units, default infinite): how far an
occluder counts.

Calls to the job's scene, per batch: CameraRays, Intersect, Occluded.
"""

from __future__ import annotations

import math

import numpy as np

from yarf_component import Frame, SceneView, Transport, normalize
from yarf_component.rays import offset_origins
from yarf_component.transport import FIRST_FREE
from yarf_component.warps import cosine_hemisphere

DIRECTION = FIRST_FREE


class AmbientOcclusion(Transport):
    class_name = "py_ambient_occlusion"
    summary = "Ambient occlusion: visibility of a cosine-distributed direction, in Python"

    def __init__(self, distance: float = math.inf) -> None:
        if not distance > 0:
            raise ValueError("property 'distance' must be > 0")
        self.distance = distance

    def dimensions(self) -> int:
        return DIRECTION + 2

    def evaluate(self, scene: SceneView, points: np.ndarray) -> tuple[np.ndarray, bool]:
        rays = scene.camera_rays(points[:, :5])
        hits = scene.intersect(rays.origins, rays.directions, times=rays.times)
        visible = np.zeros(len(points), np.float32)
        found = hits.found
        if found.any():
            directions = rays.directions[found]
            positions = rays.origins[found] + directions * hits.t[found][:, None]
            normals = hits.normals[found]
            # The hemisphere on the side the camera ray came from.
            facing = np.where(
                (np.sum(normals * directions, axis=1) > 0)[:, None], -normals, normals
            )
            local = cosine_hemisphere(points[found, DIRECTION], points[found, DIRECTION + 1])
            towards = normalize(Frame(facing).to_world(local))
            blocked = scene.occluded(
                offset_origins(positions, facing, towards),
                towards,
                tfar=np.float32(self.distance),
                times=rays.times[found],
            )
            visible[found] = np.where(blocked, 0, 1)
        layout = scene.layout
        contributions = np.stack(
            [
                points[:, 0] * layout.width,
                points[:, 1] * layout.height,
                visible,
                visible,
                visible,
            ],
            axis=1,
        )
        return contributions, False
