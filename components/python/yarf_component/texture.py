"""The Texture interface (texture.proto): values that vary over a surface.

A texture answers batches of lookups at surface points: texture
coordinates uv [N,2] (v = 0 is an image's top row) and the footprint
[N,4] (du/dx, dv/dx, du/dy, dv/dy: how uv changes from one pixel to the
next; zeros for a point lookup). A material property whose value names the
texture reads it there, so a BSDF never asks whether a value is textured.
"""

from __future__ import annotations

import abc

import numpy as np

from yarf_component.component import Component


class Texture(Component):
    """A float (1 channel) or RGB (3 channels) texture, evaluated in batches."""

    interface_name = "yarf.v1.Texture"

    @abc.abstractmethod
    def channels(self) -> int:
        """1 (a float texture) or 3 (RGB); fixed for an instance."""

    @abc.abstractmethod
    def evaluate(self, uv: np.ndarray, footprint: np.ndarray) -> np.ndarray:
        """[N, channels()] values at uv [N,2], filtered over footprint [N,4]."""

    @abc.abstractmethod
    def mean(self) -> np.ndarray:
        """The mean over the unit square of uv: channels() values."""
