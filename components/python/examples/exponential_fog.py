"""py_exponential_fog: fog that thins with height (an exponential atmosphere), as a Python Medium.

Its coefficients at a point of height z are those at the ground, z ≤ 0,
times exp(−max(z, 0)/H), H the scale height: the density halves every
H·ln 2 upwards and stays constant below the ground. The phase function is
Henyey–Greenstein of mean cosine ``g``; the fog does not emit.

Each ray's majorant is the fog's extinction at the lowest point the ray
reaches over [0, tmax), so it bounds σ_t along the whole ray; wherever the
fog is thinner than there, tracking meets null collisions. The
transmittance of a vertical path from z = 0 to z = h is
exp(−σ_t·H·(1 − e^{−h/H})).

Properties: sigma_a, sigma_s (rgb or float, ≥ 0, default 0: the
coefficients at the ground, per unit length), scale_height (float > 0,
scene units, default 1), g (float in (-1, 1), default 0).

Serve it with
``yarf-component serve examples/exponential_fog.py:ExponentialFog --listen 127.0.0.1:0``.
"""

from __future__ import annotations

import numpy as np

from yarf_component import HenyeyGreensteinMedium, Rgb


class ExponentialFog(HenyeyGreensteinMedium):
    class_name = "py_exponential_fog"
    summary = "fog whose density falls off exponentially with height, in Python"

    def __init__(
        self,
        sigma_a: Rgb = (0.0, 0.0, 0.0),
        sigma_s: Rgb = (0.0, 0.0, 0.0),
        scale_height: float = 1.0,
        g: float = 0.0,
    ) -> None:
        if not 0 < scale_height < np.inf:
            raise ValueError("property 'scale_height' must be finite and positive")
        if not -1 < g < 1:
            raise ValueError("property 'g' must lie in (-1, 1)")
        for name, value in (("sigma_a", sigma_a), ("sigma_s", sigma_s)):
            if not all(0 <= c < np.inf for c in value):
                raise ValueError(f"property '{name}' must be finite and non-negative")
        self.sigma_a = np.array(sigma_a, np.float32)
        self.sigma_s = np.array(sigma_s, np.float32)
        self.scale_height = np.float32(scale_height)
        self.g = g

    def density(self, z: np.ndarray) -> np.ndarray:
        """exp(−max(z, 0)/H) [N] at heights z [N]."""
        return np.exp(-np.maximum(z, np.float32(0)) / self.scale_height).astype(np.float32)

    def majorants(
        self, origin: np.ndarray, direction: np.ndarray, tmax: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        sigma_t = self.sigma_a + self.sigma_s
        covered = tmax > 0 if sigma_t.max() > 0 else np.zeros(len(tmax), bool)
        # The density falls with z: its maximum over the ray is at the ray's
        # lowest point, its end when it goes down (−∞ for an endless ray).
        down = direction[:, 2] < 0
        with np.errstate(invalid="ignore", over="ignore"):
            lowest = np.where(down, origin[:, 2] + direction[:, 2] * tmax, origin[:, 2])
        segments = np.zeros((int(covered.sum()), 5), np.float32)
        segments[:, 1] = tmax[covered]
        segments[:, 2:] = self.density(lowest[covered])[:, None] * sigma_t
        offsets = np.concatenate([[0], np.cumsum(covered)]).astype(np.uint32)
        return segments, offsets

    def coefficients(self, position: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        density = self.density(position[:, 2])[:, None]
        return density * self.sigma_a, density * self.sigma_s, np.zeros_like(position)
