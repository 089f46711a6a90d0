"""py_lambertian: the ideal diffuse reflector, as a Python SurfaceModel.

The same model as yarfd's C++ ``lambertian``: f(wi, wo) = reflectance / π
when wi and wo lie on the same side of the surface, 0 otherwise. Both
sides reflect alike (two-sided); nothing is transmitted. Sample draws wo
from the cosine-weighted hemisphere on wi's side, so its weight is the
reflectance itself; a wi in the tangent plane (z = 0), or an ``allowed``
that excludes the reflect-diffuse lobe, draws nothing.

Property: reflectance (rgb or float, each channel in [0, 1]; default 0.5).

Serve it with ``yarf-component serve examples/lambertian.py:Lambertian --listen 127.0.0.1:0``.
"""

from __future__ import annotations

import numpy as np

from yarf_component import Rgb, ScatterFlags, SurfaceModel, TransportMode, lobe_allowed
from yarf_component.warps import INV_PI, cosine_hemisphere, cosine_hemisphere_pdf

LOBE = ScatterFlags.REFLECT | ScatterFlags.DIFFUSE


class Lambertian(SurfaceModel):
    class_name = "py_lambertian"
    summary = "Ideal diffuse (Lambertian) reflection, two-sided, in Python"

    def __init__(self, reflectance: Rgb = (0.5, 0.5, 0.5)) -> None:
        self.reflectance = np.array(reflectance, dtype=np.float32)
        if not np.all((self.reflectance >= 0) & (self.reflectance <= 1)):
            raise ValueError("property 'reflectance' must lie in [0, 1] in every channel")

    def lobes(self) -> int:
        return LOBE

    def evaluate(
        self, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray, mode: TransportMode
    ) -> np.ndarray:
        same_side = (wi[:, 2] * wo[:, 2] > 0)[:, None]
        return np.where(same_side, self.reflectance * INV_PI, np.float32(0))

    def sample(
        self,
        wi: np.ndarray,
        uv: np.ndarray,
        uniform: np.ndarray,
        allowed: ScatterFlags,
        mode: TransportMode,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        wo = cosine_hemisphere(uniform[:, 1], uniform[:, 2])
        # Mirror onto wi's side: the back face reflects like the front.
        np.copysign(wo[:, 2], wi[:, 2], out=wo[:, 2])
        density = np.abs(wo[:, 2]) * INV_PI
        # f·|cos θo| / pdf = (ρ/π)·cos θo / (cos θo/π): the weight is ρ.
        weight = np.broadcast_to(self.reflectance, wo.shape)
        flags = np.full(len(wo), LOBE, np.uint32)
        drawn = (wi[:, 2] != 0) & (density > 0)
        if not lobe_allowed(LOBE, allowed):
            drawn[:] = False
        if not drawn.all():
            missed = ~drawn
            wo[missed] = 0
            density[missed] = 0
            flags[missed] = 0
            weight = np.where(drawn[:, None], weight, np.float32(0))
        return wo, weight, density, flags

    def pdf(self, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray) -> np.ndarray:
        same_side = wi[:, 2] * wo[:, 2] > 0
        return np.where(same_side, cosine_hemisphere_pdf(np.abs(wo[:, 2])), np.float32(0))
