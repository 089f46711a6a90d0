"""Vectorised sampling warps for component authors, as yarfd's C++ components use them.

Each takes uniform numbers in [0,1) as float32 arrays [N] and returns
directions [N,3] in a local frame whose +z is the axis; each pdf is per
solid angle and 0 outside the warp's image.
"""

from __future__ import annotations

import numpy as np

INV_PI = np.float32(1 / np.pi)
TWO_PI = np.float32(2 * np.pi)


def concentric_disk(u0: np.ndarray, u1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shirley and Chiu's map of the square onto the unit disk: (x [N], y [N])."""
    a = np.asarray(u0, np.float32) * np.float32(2) - np.float32(1)
    b = np.asarray(u1, np.float32) * np.float32(2) - np.float32(1)
    wide = np.abs(a) > np.abs(b)
    r = np.where(wide, a, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(wide, b, a) / r
    # The centre (r = 0) maps to itself: any angle will do.
    ratio[r == 0] = 0
    quarter = np.float32(np.pi / 4)
    phi = np.where(wide, quarter * ratio, np.float32(np.pi / 2) - quarter * ratio)
    return r * np.cos(phi), r * np.sin(phi)


def cosine_hemisphere(u0: np.ndarray, u1: np.ndarray) -> np.ndarray:
    """Directions [N,3] about +z with density cos θ / π (Malley's method)."""
    x, y = concentric_disk(u0, u1)
    out = np.empty((len(x), 3), np.float32)
    out[:, 0] = x
    out[:, 1] = y
    out[:, 2] = np.sqrt(np.maximum(np.float32(0), 1 - x * x - y * y))
    return out


def cosine_hemisphere_pdf(cos_theta: np.ndarray) -> np.ndarray:
    cos_theta = np.asarray(cos_theta, np.float32)
    return np.where(cos_theta > 0, cos_theta * INV_PI, np.float32(0)).astype(np.float32)


def spherical_direction(cos_theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit vectors [N,3] at polar angle θ (given by cos θ) and azimuth φ."""
    cos_theta = np.asarray(cos_theta, np.float32)
    sin_theta = np.sqrt(np.maximum(np.float32(0), 1 - cos_theta * cos_theta))
    return np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=1).astype(
        np.float32
    )


def phong_lobe(u0: np.ndarray, u1: np.ndarray, exponent: float) -> np.ndarray:
    """Directions [N,3] about +z with density ∝ cos^n θ: cos θ = u0^(1/(n+1))."""
    cos_theta = np.power(np.asarray(u0, np.float32), np.float32(1 / (exponent + 1)))
    return spherical_direction(cos_theta, TWO_PI * np.asarray(u1, np.float32))


def phong_lobe_pdf(cos_theta: np.ndarray, exponent: float) -> np.ndarray:
    cos_theta = np.asarray(cos_theta, np.float32)
    positive = np.maximum(cos_theta, np.float32(0))
    value = np.float32((exponent + 1) / (2 * np.pi)) * np.power(positive, np.float32(exponent))
    return np.where(cos_theta > 0, value, np.float32(0)).astype(np.float32)
