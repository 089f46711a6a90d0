"""What GetJob tells of a job's scene: its size and what it holds.

The same counts as yarfd's (server/src/service/scene_summary.cc), so that
a job page reads alike whichever server ran the job.
"""

from __future__ import annotations

from yarf.scene import iter_shapes
from yarf.v1 import render_pb2, scene_pb2


def summarize_scene(scene: scene_pb2.Scene) -> render_pb2.SceneSummary:
    """The film's size and how many shapes, instances, materials, lights, textures and
    media ``scene`` holds; a group's shapes count once however often it is placed."""
    shapes = [shape for _, shape in iter_shapes(scene)]
    emitting = sum(shape.HasField("emitter") for shape in shapes)
    return render_pb2.SceneSummary(
        width=scene.film.width,
        height=scene.film.height,
        shapes=len(shapes),
        instances=len(scene.instances) + sum(len(group.instances) for group in scene.groups),
        materials=len(scene.materials),
        lights=len(scene.lights) + emitting,
        textures=len(scene.textures),
        media=len(scene.media),
        camera=scene_pb2.Camera.Model.Name(scene.camera.model).lower(),
    )
