"""py_phong: the modified Phong reflection model, as a Python SurfaceModel.

The same model as yarfd's C++ ``phong`` (Lafortune & Willems 1994), a
diffuse term plus a glossy lobe about the mirror direction:

    f(wi, wo) = kd / π + ks · (n + 2) / (2π) · cos^n α

with α the angle between wo and the mirror direction of wi (the lobe is 0
beyond 90°). Two-sided; wi and wo on opposite sides give 0. Sample picks
one of the allowed lobes with probability proportional to the luminance
of kd and ks, draws wo from the cosine-weighted hemisphere or the cos^n
lobe, and returns the density of the mixture of the allowed lobes (and
their value in the weight); a glossy direction below the surface draws
nothing.

Properties:
    diffuse_reflectance    rgb (or float), default 0.5   kd, each channel in [0, 1]
    specular_reflectance   rgb (or float), default 0.2   ks, each channel in [0, 1]
    exponent               float, default 30             n ≥ 0; larger is shinier
kd + ks must not exceed 1 in any channel.
"""

from __future__ import annotations

import math

import numpy as np

from yarf_component import Frame, Rgb, ScatterFlags, SurfaceModel, TransportMode, lobe_allowed
from yarf_component.frames import reflect
from yarf_component.warps import (
    INV_PI,
    cosine_hemisphere,
    cosine_hemisphere_pdf,
    phong_lobe,
    phong_lobe_pdf,
)

DIFFUSE_LOBE = ScatterFlags.REFLECT | ScatterFlags.DIFFUSE
GLOSSY_LOBE = ScatterFlags.REFLECT | ScatterFlags.GLOSSY
CHANNELS = ("red", "green", "blue")


def luminance(rgb: np.ndarray) -> float:
    return float(0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2])


def reflectance(name: str, value: tuple[float, float, float]) -> np.ndarray:
    rgb = np.array(value, dtype=np.float32)
    if not np.all((rgb >= 0) & (rgb <= 1)):
        raise ValueError(f"property '{name}' must lie in [0, 1] in every channel")
    return rgb


class Phong(SurfaceModel):
    class_name = "py_phong"
    summary = "Modified Phong (Lafortune & Willems 1994): diffuse plus a glossy lobe, in Python"

    def __init__(
        self,
        diffuse_reflectance: Rgb = (0.5, 0.5, 0.5),
        specular_reflectance: Rgb = (0.2, 0.2, 0.2),
        exponent: float = 30.0,
    ) -> None:
        self.diffuse = reflectance("diffuse_reflectance", diffuse_reflectance)
        self.specular = reflectance("specular_reflectance", specular_reflectance)
        if not (exponent >= 0 and math.isfinite(exponent)):
            raise ValueError("property 'exponent' must be a finite number ≥ 0")
        self.exponent = float(np.float32(exponent))
        for channel, total in zip(CHANNELS, self.diffuse + self.specular, strict=True):
            if total > 1:
                raise ValueError(
                    "properties 'diffuse_reflectance' + 'specular_reflectance' exceed 1 in the "
                    f"{channel} channel: the material would create energy"
                )
        # The odds of sampling each lobe.
        self.diffuse_weight = luminance(self.diffuse)
        self.specular_weight = luminance(self.specular)
        total = self.diffuse_weight + self.specular_weight
        self.specular_probability = self.specular_weight / total if total > 0 else 0.0

    def lobes(self) -> int:
        return (DIFFUSE_LOBE if self.diffuse_weight > 0 else 0) | (
            GLOSSY_LOBE if self.specular_weight > 0 else 0
        )

    @staticmethod
    def _cos_to_mirror(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        # Symmetric in wi and wo (reciprocal) and unchanged by mirroring both
        # to the other side (two-sided).
        return np.sum(wo * reflect(wi), axis=1)

    def _value(self, wi: np.ndarray, wo: np.ndarray, diffuse: bool, glossy: bool) -> np.ndarray:
        """f of the lobes asked for."""
        cos_alpha = self._cos_to_mirror(wi, wo)
        n = self.exponent
        lobe = np.float32((n + 2) / (2 * np.pi)) * np.power(
            np.maximum(cos_alpha, np.float32(0)), np.float32(n)
        )
        lobe = np.where(glossy & (cos_alpha > 0), lobe, np.float32(0))
        value = self.specular * lobe[:, None]
        if diffuse:
            value = value + self.diffuse * INV_PI
        return np.where((wi[:, 2] * wo[:, 2] > 0)[:, None], value, np.float32(0))

    def _density(self, wi: np.ndarray, wo: np.ndarray, specular_probability: float) -> np.ndarray:
        """Density of the lobe mixture; the glossy lobe's part below the surface is lost."""
        p = np.float32(specular_probability)
        density = (1 - p) * cosine_hemisphere_pdf(np.abs(wo[:, 2])) + p * phong_lobe_pdf(
            self._cos_to_mirror(wi, wo), self.exponent
        )
        return np.where(wi[:, 2] * wo[:, 2] > 0, density, np.float32(0))

    def evaluate(
        self, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray, mode: TransportMode
    ) -> np.ndarray:
        return self._value(wi, wo, True, True)

    def sample(
        self,
        wi: np.ndarray,
        uv: np.ndarray,
        uniform: np.ndarray,
        allowed: ScatterFlags,
        mode: TransportMode,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        diffuse = lobe_allowed(DIFFUSE_LOBE, allowed) and self.diffuse_weight > 0
        glossy = lobe_allowed(GLOSSY_LOBE, allowed) and self.specular_weight > 0
        total = (self.diffuse_weight if diffuse else 0.0) + (
            self.specular_weight if glossy else 0.0
        )
        specular_probability = (self.specular_weight if glossy else 0.0) / total if total else 0.0
        specular = uniform[:, 0] < np.float32(specular_probability)
        # The glossy lobe is symmetric about the mirror direction: sample it
        # in a frame whose z axis is that direction.
        glossy_wo = Frame(reflect(wi)).to_world(
            phong_lobe(uniform[:, 1], uniform[:, 2], self.exponent)
        )
        diffuse_wo = cosine_hemisphere(uniform[:, 1], uniform[:, 2])
        diffuse_wo[:, 2] = np.where(wi[:, 2] < 0, -diffuse_wo[:, 2], diffuse_wo[:, 2])
        wo = np.where(specular[:, None], glossy_wo, diffuse_wo)
        if total > 0:
            density = self._density(wi, wo, specular_probability)
        else:
            density = np.zeros(len(wi), np.float32)
        drawn = density > 0
        safe = np.where(drawn, density, np.float32(1))
        weight = self._value(wi, wo, diffuse, glossy) * (np.abs(wo[:, 2]) / safe)[:, None]
        flags = np.where(specular, np.uint32(GLOSSY_LOBE), np.uint32(DIFFUSE_LOBE))
        column = drawn[:, None]
        return (
            np.where(column, wo, np.float32(0)),
            np.where(column, weight, np.float32(0)),
            np.where(drawn, density, np.float32(0)),
            np.where(drawn, flags, np.uint32(0)),
        )

    def pdf(self, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray) -> np.ndarray:
        return self._density(wi, wo, self.specular_probability)
