"""A transport that renders nothing but, when a job prepares it, asks the job's
SceneView everything it answers and writes the answers, as JSON, to the file
its ``report`` property names: what the tests check against the scene they
submitted."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
from yarf_component import SceneView, SceneViewError, Transport
from yarf_component.transport import FIRST_FREE

SAMPLES = 512


def listed(values: np.ndarray) -> list:
    return np.asarray(values, dtype=np.float64).tolist()


def refusal(call: Callable[[], object]) -> str:
    """The message of the SceneViewError the call raises; empty when it succeeds."""
    try:
        call()
    except SceneViewError as error:
        return str(error)
    return ""


class SceneProbe(Transport):
    class_name = "scene_probe"
    summary = "Reports what the job's SceneView answers"

    def __init__(self, report: str = "") -> None:
        self.report = Path(report)

    def dimensions(self) -> int:
        return FIRST_FREE

    def prepare(self, scene: SceneView) -> None:
        layout = scene.layout
        rng = np.random.default_rng(7)
        shapes = np.arange(len(layout.material_handles), dtype=np.uint32)
        answers: dict[str, object] = {
            "layout": {
                "width": layout.width,
                "height": layout.height,
                "shape_emitters": listed(layout.shape_emitters),
                "primitive_counts": listed(layout.primitive_counts),
                "media_boundaries": listed(layout.media_boundaries),
                "interior_media": listed(layout.interior_media),
                "exterior_media": listed(layout.exterior_media),
                "has_lights": layout.has_lights,
                "has_environment": layout.has_environment,
                "light_count": layout.light_count,
                "emitters": len(layout.emitter_handles),
                "media": len(layout.medium_handles),
                "camera_medium": layout.camera_medium,
                "camera_has_lens": layout.camera_has_lens,
                "camera_unreachable_reason": layout.camera_unreachable_reason,
            },
            "triangle_areas": [
                float(
                    np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum() / 2
                )
                for t in (scene.triangles(int(s)) for s in shapes)
            ],
            "shape_areas": [scene.shape_area(int(s)) for s in shapes],
            "light_pdf_area": listed(scene.light_pdf_area(shapes)),
        }
        if layout.has_lights:
            starts = scene.sample_light_points(rng.random((SAMPLES, 3), np.float32))
            answers["light_points"] = {
                name: listed(getattr(starts, name))
                for name in ("pdf", "flags", "emitters", "shape_ids", "positions", "normals")
            }
            seen_from = np.tile(np.array([[0.0, 1.0, 0.0]], np.float32), (layout.light_count, 1))
            gathered = scene.light_points(np.arange(layout.light_count), seen_from)
            answers["gathered"] = {
                name: listed(getattr(gathered, name))
                for name in ("pdf", "distances", "radiance", "emitters", "positions")
            }
            up = np.tile(np.array([[0.0, 0.0, 1.0]], np.float32), (4, 1))
            answers["emitter_radiance"] = listed(
                scene.emitter(0).radiance(up, np.zeros((4, 2), np.float32))
            )
        points = rng.random((SAMPLES, 5), np.float32)
        rays = scene.camera_rays(points)
        hits = scene.intersect(rays.origins, rays.directions, times=rays.times)
        found = hits.found
        at = rays.origins[found] + rays.directions[found] * hits.t[found][:, None]
        seen = scene.connect_to_camera(at, points[found, 2:4])
        dpdx, dpdy = scene.sample_spacing(at, hits.normals[found])
        answers["camera"] = {
            "film": listed(points[found, :2] * [layout.width, layout.height]),
            "connected": listed(seen.connected),
            "raster": listed(seen.raster),
            "importance": listed(seen.importance),
            "direction_pdf": listed(scene.camera_direction_pdf(rays.directions[found])),
            "spacing": listed(np.linalg.norm(dpdx, axis=1) + np.linalg.norm(dpdy, axis=1)),
            "shutter": listed(scene.shutter_times(np.array([0.0, 0.5, 0.99], np.float32))),
        }
        # Every hit along the camera rays, and along one ray straight down
        # through the whole scene from far above it.
        down = np.array([[278, 5000, 279.5]], np.float32), np.array([[0, -1, 0]], np.float32)
        crossings = scene.cross_section(
            np.concatenate([rays.origins[:64], down[0]]),
            np.concatenate([rays.directions[:64], down[1]]),
            times=np.concatenate([rays.times[:64], [0]]),
        )
        answers["cross_section"] = {
            "rays": [listed(np.stack(crossings.of(k))) for k in range(65)],
            "closest_t": listed(hits.t[:64]),
            "closest_shape": listed(hits.shape_ids[:64]),
        }
        directions = np.array([[0, 0, -1], [0, 1, 0], [1, 0, 0]], np.float32)
        origins, pdf = scene.infinite_light_origins(directions, np.full((3, 2), 0.5, np.float32))
        answers["infinite"] = {"origins": listed(origins), "pdf": listed(pdf)}
        if len(layout.medium_handles):
            fog = scene.medium(0)
            origin = np.zeros((1, 3), np.float32)
            sigma_a, sigma_s, _ = fog.coefficients(origin)
            segments, offsets = fog.majorants(origin, np.array([[0, 0, 1]], np.float32), 10.0)
            up, down = np.array([[0, 0, 1]], np.float32), np.array([[0, 0, -1]], np.float32)
            phase, phase_pdf = fog.evaluate_phase(up, down, origin)
            answers["medium"] = {
                "sigma_a": listed(sigma_a[0]),
                "sigma_s": listed(sigma_s[0]),
                "emits": fog.emits,
                "segments": listed(segments),
                "offsets": listed(offsets),
                "phase": listed(phase),
                "phase_pdf": listed(phase_pdf),
            }
        answers["errors"] = {
            "shape": refusal(lambda: scene.light_pdf_area(np.array([10**6], np.uint32))),
            "direction": refusal(
                lambda: scene.camera_direction_pdf(np.array([[np.nan, 0, 1]], np.float32))
            ),
            "lens": refusal(
                lambda: scene.connect_to_camera(np.zeros((1, 3)), np.full((1, 2), 2.0))
            ),
            "light": refusal(lambda: scene.light_points(np.array([10**6]), np.zeros((1, 3)))),
        }
        self.report.write_text(json.dumps(answers))

    def evaluate(self, scene: SceneView, points: np.ndarray) -> tuple[np.ndarray, bool]:
        return np.zeros((0, 5), np.float32), True
