"""py_checkerboard: Mitsuba's checkerboard texture, as a Python Texture.

The same pattern as yarfd's C++ ``checkerboard`` with Mitsuba's
properties: uv is mapped by ``to_uv`` and wrapped into the unit square,
which holds 2 × 2 checks; color0 where u and v fall in halves of the
same parity, color1 elsewhere. Point lookups: the footprint is ignored.

Properties: color0 (rgb, default 0.4), color1 (rgb, default 0.2),
to_uv (transform; its 2-D affine part maps uv, default identity).

Serve it with ``yarf-component serve examples/checkerboard.py:Checkerboard --listen 127.0.0.1:0``.
"""

from __future__ import annotations

import numpy as np

from yarf_component import Rgb, SurfacePoints, Texture, Transform


class Checkerboard(Texture):
    class_name = "py_checkerboard"
    summary = "Mitsuba's 2 x 2 checkerboard texture, in Python"

    def __init__(
        self,
        color0: Rgb = (0.4, 0.4, 0.4),
        color1: Rgb = (0.2, 0.2, 0.2),
        to_uv: Transform | None = None,
    ) -> None:
        self.color0 = np.array(color0, dtype=np.float32)
        self.color1 = np.array(color1, dtype=np.float32)
        matrix = np.eye(4) if to_uv is None else np.asarray(to_uv, dtype=np.float64).reshape(4, 4)
        # u' = a·u + b·v + c, v' = d·u + e·v + f: the affine part on (u, v).
        self.linear = matrix[:2, :2]
        self.offset = matrix[:2, 3]

    def channels(self) -> int:
        return 3

    def evaluate(self, at: SurfacePoints) -> np.ndarray:
        mapped = at.uv.astype(np.float64) @ self.linear.T + self.offset
        halves = (mapped - np.floor(mapped)) > 0.5
        same = halves[:, 0] == halves[:, 1]
        return np.where(same[:, None], self.color0, self.color1).astype(np.float32)

    def mean(self) -> np.ndarray:
        return (self.color0 + self.color1) / 2
