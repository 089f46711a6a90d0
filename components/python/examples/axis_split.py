"""py_axis_split: two colours either side of a plane in the world, as a Python Texture.

A texture of where a point is, not of its uv: ``above`` where the point's
world coordinate along ``axis`` exceeds ``offset``, ``below`` elsewhere.
Where yarfd knows no position (a point on a light, a mesh without uvs:
SurfacePoints.position is None) it gives the mean of the two.

Properties: axis ("x", "y" or "z", default "x"), offset (float, scene
units, default 0), above (rgb, default (0.8, 0.2, 0.2)), below (rgb,
default (0.2, 0.8, 0.2)).

Serve it with ``yarf-component serve examples/axis_split.py:AxisSplit --listen 127.0.0.1:0``.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from yarf_component import Rgb, SurfacePoints, Texture


class AxisSplit(Texture):
    class_name = "py_axis_split"
    summary = "one colour on each side of a plane x, y or z = offset, in Python"

    def __init__(
        self,
        axis: Literal["x", "y", "z"] = "x",
        offset: float = 0.0,
        above: Rgb = (0.8, 0.2, 0.2),
        below: Rgb = (0.2, 0.8, 0.2),
    ) -> None:
        self.axis = "xyz".index(axis)
        self.offset = offset
        self.above = np.array(above, dtype=np.float32)
        self.below = np.array(below, dtype=np.float32)

    def channels(self) -> int:
        return 3

    def evaluate(self, at: SurfacePoints) -> np.ndarray:
        if at.position is None:
            return np.tile(self.mean(), (len(at.uv), 1))
        beyond = at.position[:, self.axis] > self.offset
        return np.where(beyond[:, None], self.above, self.below).astype(np.float32)

    def mean(self) -> np.ndarray:
        return (self.above + self.below) / 2
