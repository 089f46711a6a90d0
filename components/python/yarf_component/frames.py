"""Orthonormal frames about normals, for taking directions to and from a local shading frame."""

from __future__ import annotations

import numpy as np


class Frame:
    """Bases (s, t, n) of N unit normals [N,3], n the +z axis (Duff et al. 2017, as
    yarfd's C++ Frame, so that both sides agree on the local x and y)."""

    def __init__(self, normals: np.ndarray) -> None:
        n = np.asarray(normals, np.float32).reshape(-1, 3)
        sign = np.copysign(np.float32(1), n[:, 2])
        a = -1 / (sign + n[:, 2])
        b = n[:, 0] * n[:, 1] * a
        self.n = n
        self.s = np.stack([1 + sign * n[:, 0] * n[:, 0] * a, sign * b, -sign * n[:, 0]], axis=1)
        self.t = np.stack([b, sign + n[:, 1] * n[:, 1] * a, -n[:, 1]], axis=1)

    def to_local(self, v: np.ndarray) -> np.ndarray:
        """World directions [N,3] in the frames' coordinates."""
        return np.stack(
            [np.sum(v * self.s, axis=1), np.sum(v * self.t, axis=1), np.sum(v * self.n, axis=1)],
            axis=1,
        ).astype(np.float32)

    def to_world(self, v: np.ndarray) -> np.ndarray:
        """Local directions [N,3] in world coordinates."""
        return (self.s * v[:, 0:1] + self.t * v[:, 1:2] + self.n * v[:, 2:3]).astype(np.float32)


def reflect(w: np.ndarray) -> np.ndarray:
    """Mirror directions [N,3] about the normal +z."""
    return (w * np.array([-1, -1, 1], np.float32)).astype(np.float32)


def normalize(v: np.ndarray) -> np.ndarray:
    """Rows scaled to unit length (zero rows stay zero)."""
    length = np.linalg.norm(v, axis=1, keepdims=True)
    return np.divide(v, length, out=np.zeros_like(v), where=length > 0).astype(np.float32)
