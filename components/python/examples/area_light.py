"""py_area_light: a uniform one-sided area light, as a Python Emitter.

The same emission as yarfd's C++ ``diffuse_area`` with a constant
radiance: the same radiance in every direction of the front (+z, the side
the shape's normal points to) and none from the back. SampleDirection
draws the cosine-weighted front hemisphere (emitted power goes as cos θ),
for paths that start at the light.

Property: radiance (rgb or float, each channel >= 0; required).

Attach it to a shape of a scene as its emitter (SceneShape.emitter) and
serve it with ``yarf-component serve examples/area_light.py:AreaLight``.
"""

from __future__ import annotations

import numpy as np

from yarf_component import Emitter, Rgb
from yarf_component.warps import cosine_hemisphere, cosine_hemisphere_pdf


class AreaLight(Emitter):
    class_name = "py_area_light"
    summary = "Uniform one-sided area light, in Python"

    def __init__(self, radiance: Rgb) -> None:
        self.radiance_value = np.array(radiance, dtype=np.float32)
        if not np.all(np.isfinite(self.radiance_value) & (self.radiance_value >= 0)):
            raise ValueError("property 'radiance' must be finite and >= 0 in every channel")

    def radiance(self, w: np.ndarray, uv: np.ndarray) -> np.ndarray:
        front = (w[:, 2] > 0)[:, None]
        return np.where(front, self.radiance_value, np.float32(0)).astype(np.float32)

    def sample_direction(self, uniform: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        w = cosine_hemisphere(uniform[:, 0], uniform[:, 1])
        return w, cosine_hemisphere_pdf(w[:, 2])

    def pdf_direction(self, w: np.ndarray) -> np.ndarray:
        return cosine_hemisphere_pdf(w[:, 2])
