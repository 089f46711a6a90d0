"""Rays that leave a surface, for transports: moved off it as yarfd's C++ transports move them,
so that float rounding does not make a ray hit the surface it starts on."""

from __future__ import annotations

import numpy as np


def surface_offset(points: np.ndarray) -> np.ndarray:
    """[N]: how far a ray starts (or stops) short of points [N,3], relative to their size."""
    return (np.float32(1e-4) * np.maximum(1, np.max(np.abs(points), axis=1))).astype(np.float32)


def offset_origins(points: np.ndarray, normals: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Origins [N,3] of rays leaving points (geometric normals [N,3]) toward directions,
    moved off the surface to the side each direction goes to."""
    side = np.where(np.sum(normals * directions, axis=1) > 0, 1, -1).astype(np.float32)
    return (points + normals * (side * surface_offset(points))[:, None]).astype(np.float32)


def shadow_rays(
    points: np.ndarray, normals: np.ndarray, targets: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(origins, unit directions, tfar) of rays from surface points to targets [N,3] that
    leave the one surface and stop short of the other's."""
    origins = offset_origins(points, normals, targets - points)
    delta = targets - origins
    length = np.linalg.norm(delta, axis=1)
    directions = np.where(
        (length > 0)[:, None], delta / np.where(length > 0, length, 1)[:, None], normals
    )
    tfar = np.maximum(0, length - surface_offset(targets))
    return origins, directions.astype(np.float32), tfar.astype(np.float32)
