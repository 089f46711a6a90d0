"""The Medium interface (medium.proto): what fills the space between surfaces.

A medium answers, for batches of rays and points in world space, the
majorants of its extinction along rays (for null-scattering tracking,
Miller et al. 2019), its coefficients (absorption σ_a, scattering σ_s,
per unit length of the scene, RGB, and the radiance it emits where it
absorbs) and its phase function. Directions follow the interface's
convention: wi points back toward where the path came from, wo toward
where light comes from, both away from the point, so forward scattering
is wo = -wi.

``henyey_greenstein`` and ``sample_henyey_greenstein`` are the phase
function of yarfd's own media (components/cpp/media/phase.h), for media
that need no other.
"""

from __future__ import annotations

import abc

import numpy as np

from yarf_component.component import Component
from yarf_component.frames import Frame
from yarf_component.warps import TWO_PI, spherical_direction

INV_FOUR_PI = np.float32(1 / (4 * np.pi))


class Medium(Component):
    """A participating medium, evaluated in batches of N rays or points."""

    interface_name = "yarf.v1.Medium"

    @abc.abstractmethod
    def majorants(
        self, origin: np.ndarray, direction: np.ndarray, tmax: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Majorant segments of N rays over [0, tmax).

        origin, direction [N,3] float32 (direction unit), tmax [N] float32
        (may be inf) -> (segments [M,5] float32: rows (t0, t1, σ_maj r, g, b)
        over which σ_t never exceeds σ_maj, in increasing t per ray, not
        overlapping, within [0, tmax]; offsets [N+1] uint32: ray i owns rows
        offsets[i] .. offsets[i+1]-1). A ray without segments sees no medium.
        A majorant above σ_t is allowed (the difference is null collisions),
        one below it is not.
        """

    @abc.abstractmethod
    def coefficients(self, position: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """position [N,3] -> (sigma_a, sigma_s, emission), each [N,3], non-negative.

        emission is the radiance emitted where the medium absorbs (the source
        term is σ_a·Le, pbrt-v4's Le); zero for a medium that does not emit.
        """

    def emits(self) -> bool:
        """Whether coefficients may ever report emission; fixed for an instance."""
        return False

    @abc.abstractmethod
    def evaluate_phase(
        self, wi: np.ndarray, wo: np.ndarray, position: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """wi, wo, position [N,3] -> (value [N]: p(wi, wo) in 1/sr, pdf [N]:
        the solid-angle density sample_phase has for wo)."""

    @abc.abstractmethod
    def sample_phase(
        self, wi: np.ndarray, position: np.ndarray, uniform: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """wi, position [N,3], uniform [N,2] in [0,1) -> (wo [N,3] unit,
        weight [N]: p/pdf, pdf [N])."""


class HenyeyGreensteinMedium(Medium):
    """A Medium whose phase function is Henyey–Greenstein of mean cosine
    ``self.g`` everywhere (0: isotropic), sampled exactly: the phase half of
    the interface for every such medium, as yarfd's C++ media share theirs."""

    g: float = 0.0

    def evaluate_phase(
        self, wi: np.ndarray, wo: np.ndarray, position: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        p = henyey_greenstein(wi, wo, self.g)
        return p, p

    def sample_phase(
        self, wi: np.ndarray, position: np.ndarray, uniform: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        wo = sample_henyey_greenstein(wi, uniform, self.g)
        # Sampled exactly: the weight p/pdf is 1.
        return wo, np.ones(len(wi), np.float32), henyey_greenstein(wi, wo, self.g)


def henyey_greenstein(wi: np.ndarray, wo: np.ndarray, g: float) -> np.ndarray:
    """p(wi, wo) [N] = (1 − g²) / (4π (1 + g² − 2gμ)^{3/2}), μ = −wi·wo; g > 0 scatters forward."""
    mu = -np.sum(np.asarray(wi, np.float32) * np.asarray(wo, np.float32), axis=1)
    g = np.float32(g)
    denominator = 1 + g * g - 2 * g * mu
    return (
        (1 - g * g) * INV_FOUR_PI / (denominator * np.sqrt(np.maximum(denominator, 1e-12)))
    ).astype(np.float32)


def sample_henyey_greenstein(wi: np.ndarray, uniform: np.ndarray, g: float) -> np.ndarray:
    """wo [N,3] distributed as henyey_greenstein(wi, ·, g), for uniform [N,2]."""
    u0 = np.asarray(uniform[:, 0], np.float32)
    if abs(g) < 1e-3:
        mu = 1 - 2 * u0
    else:
        g = np.float32(g)
        s = (1 - g * g) / (1 - g + 2 * g * u0)
        mu = np.clip((1 + g * g - s * s) / (2 * g), -1, 1)
    # The light travelled along -wo and leaves along wi: -wo lies at angle
    # acos μ about wi.
    travel = Frame(wi).to_world(
        spherical_direction(mu, TWO_PI * np.asarray(uniform[:, 1], np.float32))
    )
    return (-travel).astype(np.float32)
