"""py_mesh_attribute: a value stored with a mesh, per vertex or per face, as a Python Texture.

As yarfd's C++ ``mesh_attribute`` (Mitsuba's): the attribute ``name`` of
the shape a point lies on, a vertex attribute interpolated over its
triangle, a face attribute its triangle's value, scaled by ``scale``. The
texture names the attribute in ``attributes()`` and yarfd reads it at
every point it sends (SurfacePoints.attributes); points on shapes without
it, or that yarfd cannot place on a shape, read 0.

Properties: name (str, required: "vertex_…" or "face_…"), scale (float,
default 1). Channels: 3. Mean: 0.5 in each channel, a stand-in, as the
C++ one: the texture alone cannot know the meshes it is used on.

Serve it with
``yarf-component serve examples/mesh_attribute.py:MeshAttribute --listen 127.0.0.1:0``.
"""

from __future__ import annotations

import math

import numpy as np

from yarf_component import SurfacePoints, Texture


class MeshAttribute(Texture):
    class_name = "py_mesh_attribute"
    summary = "a mesh's per-vertex or per-face attribute, in Python"

    def __init__(self, name: str, scale: float = 1.0) -> None:
        if not name.startswith(("vertex_", "face_")):
            raise ValueError(f"property 'name' must start with 'vertex_' or 'face_', got '{name}'")
        if not math.isfinite(scale):
            raise ValueError("property 'scale' must be finite")
        self.name = name
        self.scale = scale

    def channels(self) -> int:
        return 3

    def attributes(self) -> list[str]:
        return [self.name]

    def evaluate(self, at: SurfacePoints) -> np.ndarray:
        return at.attributes[self.name] * np.float32(self.scale)

    def mean(self) -> np.ndarray:
        return np.full(3, 0.5, np.float32)
