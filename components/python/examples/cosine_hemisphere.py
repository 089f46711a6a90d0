"""py_cosine_hemisphere: directions of z > 0 with density cos θ / π, as a Python Warp.

Malley's method, as yarfd's cosine_hemisphere: a uniform point of the
unit disk (Shirley and Chiu's concentric map) lifted straight up onto the
hemisphere. [0,1)² -> unit vectors (x, y, z), pdf cos θ / π per
steradian, 0 for z ≤ 0. No inverse. No properties.
"""

from __future__ import annotations

import numpy as np

from yarf_component import Warp
from yarf_component.warps import cosine_hemisphere, cosine_hemisphere_pdf


class CosineHemisphere(Warp):
    class_name = "py_cosine_hemisphere"
    summary = "Cosine-weighted directions of the hemisphere (Malley)"
    domain_dimensions = 2
    image_dimensions = 3

    def forward(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        directions = cosine_hemisphere(points[:, 0], points[:, 1])
        return directions, cosine_hemisphere_pdf(directions[:, 2])

    def pdf(self, points: np.ndarray) -> np.ndarray:
        return cosine_hemisphere_pdf(points[:, 2])
