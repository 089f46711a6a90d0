"""py_homogeneous: a medium with the same coefficients everywhere, as a Python Medium.

The same medium as yarfd's C++ ``homogeneous``: absorption σ_a and
scattering σ_s per unit length of the scene, the radiance ``emission``
emitted where it absorbs, and a Henyey–Greenstein phase function of mean
cosine ``g``. Its majorant is its own extinction σ_t = σ_a + σ_s over the
whole ray, so tracking through it never meets a null collision.

Properties: sigma_a, sigma_s (rgb or float, ≥ 0, default 0), scale (float,
multiplies both, ≥ 0, default 1), emission (rgb or float, ≥ 0, default 0),
g (float in (-1, 1), default 0: isotropic).

Serve it with ``yarf-component serve examples/homogeneous.py:Homogeneous --listen 127.0.0.1:0``.
"""

from __future__ import annotations

import numpy as np

from yarf_component import HenyeyGreensteinMedium, Rgb


class Homogeneous(HenyeyGreensteinMedium):
    class_name = "py_homogeneous"
    summary = "the same absorption, scattering and phase function everywhere, in Python"

    def __init__(
        self,
        sigma_a: Rgb = (0.0, 0.0, 0.0),
        sigma_s: Rgb = (0.0, 0.0, 0.0),
        scale: float = 1.0,
        emission: Rgb = (0.0, 0.0, 0.0),
        g: float = 0.0,
    ) -> None:
        if not (0 <= scale < np.inf):
            raise ValueError("property 'scale' must be finite and non-negative")
        if not -1 < g < 1:
            raise ValueError("property 'g' must lie in (-1, 1)")
        for name, value in (("sigma_a", sigma_a), ("sigma_s", sigma_s), ("emission", emission)):
            if not all(0 <= c < np.inf for c in value):
                raise ValueError(f"property '{name}' must be finite and non-negative")
        self.sigma_a = np.array(sigma_a, np.float32) * np.float32(scale)
        self.sigma_s = np.array(sigma_s, np.float32) * np.float32(scale)
        self.emission = np.array(emission, np.float32)
        self.g = g

    def majorants(
        self, origin: np.ndarray, direction: np.ndarray, tmax: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        sigma_t = self.sigma_a + self.sigma_s
        covered = tmax > 0 if sigma_t.max() > 0 else np.zeros(len(tmax), bool)
        segments = np.zeros((int(covered.sum()), 5), np.float32)
        segments[:, 1] = tmax[covered]
        segments[:, 2:] = sigma_t
        offsets = np.concatenate([[0], np.cumsum(covered)]).astype(np.uint32)
        return segments, offsets

    def coefficients(self, position: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        n = len(position)
        return (
            np.tile(self.sigma_a, (n, 1)),
            np.tile(self.sigma_s, (n, 1)),
            np.tile(self.emission, (n, 1)),
        )

    def emits(self) -> bool:
        return bool(self.emission.max() > 0 and self.sigma_a.max() > 0)
