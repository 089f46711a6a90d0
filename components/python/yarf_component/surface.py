"""Surface interfaces (surface.proto): SurfaceModel and Emitter, with their flags.

Every array is float32, one row per query. Directions are unit vectors in
the local shading frame: +z is the surface normal, wi points toward where
light goes (the camera side for paths from the eye), wo toward where it
comes from; both point away from the surface.
"""

from __future__ import annotations

import abc
import enum

import numpy as np

from yarf_component.component import Component


class ScatterFlags(enum.IntFlag):
    """Bits of Sample's ``flags`` and of its ``allowed`` argument (surface.proto)."""

    NONE = 0
    REFLECT = 1
    REFRACT = 2
    DELTA = 4
    DIFFUSE = 8
    GLOSSY = 16


class TransportMode(enum.IntEnum):
    """What a path carries: radiance (paths from the camera) or importance (from the lights)."""

    RADIANCE = 0
    IMPORTANCE = 1


def lobe_allowed(lobe: int, allowed: int) -> bool:
    """Whether Sample may draw a lobe with these flags: all of them accepted (0 accepts all)."""
    return allowed == 0 or (lobe & ~allowed) == 0


class SurfaceModel(Component):
    """A BSDF. Batches of N queries; no method may loop over rows in Python if it can help it."""

    interface_name = "yarf.v1.SurfaceModel"

    @abc.abstractmethod
    def lobes(self) -> int:
        """Union of the ScatterFlags of every lobe; fixed for an instance."""

    @abc.abstractmethod
    def evaluate(
        self, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray, mode: TransportMode
    ) -> np.ndarray:
        """f(wi, wo) in 1/sr, no cosine factor: [N,3] RGB from wi, wo [N,3] and uv [N,2]."""

    @abc.abstractmethod
    def sample(
        self,
        wi: np.ndarray,
        uv: np.ndarray,
        uniform: np.ndarray,
        allowed: ScatterFlags,
        mode: TransportMode,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Draws wo given wi and uniform [N,3] (lobe choice, then two for the direction).

        Returns wo [N,3], weight f·|cos θo|/pdf [N,3], pdf [N] (solid angle;
        for a delta lobe the probability of choosing it) and flags [N]
        (uint32 ScatterFlags of the lobe drawn). A row that draws nothing
        has zero wo, weight, pdf and flags. Only lobes whose flags are all
        in ``allowed`` may be drawn (0 allows every lobe).
        """

    @abc.abstractmethod
    def pdf(self, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray) -> np.ndarray:
        """[N]: the solid-angle density with which ``sample`` draws wo given wi (0 for deltas)."""


class Emitter(Component):
    """Light leaving a surface, in the emitter's local frame (+z its normal or axis)."""

    interface_name = "yarf.v1.Emitter"

    @abc.abstractmethod
    def radiance(self, w: np.ndarray, uv: np.ndarray) -> np.ndarray:
        """[N,3] RGB radiance toward w [N,3] from surface parameters uv [N,2], W·m⁻²·sr⁻¹."""

    @abc.abstractmethod
    def sample_direction(self, uniform: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Directions of emission for uniform [N,2]: w [N,3] and their solid-angle pdf [N]."""

    @abc.abstractmethod
    def pdf_direction(self, w: np.ndarray) -> np.ndarray:
        """[N]: the solid-angle density ``sample_direction`` has at w [N,3]."""
