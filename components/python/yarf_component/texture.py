"""The Texture interface (texture.proto): values that vary over a surface.

A texture answers batches of lookups at surface points (SurfacePoints):
texture coordinates and footprint always, and, where the caller knows
them, world positions, where on which shape each point lies, and the
mesh attributes the texture named in ``attributes()``. A material
property whose value names the texture reads it there, so a BSDF never
asks whether a value is textured.
"""

from __future__ import annotations

import abc
from collections.abc import Mapping
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from yarf_component.component import Component


class SurfacePoints(NamedTuple):
    """N surface points, as yarfd's SurfacePoints; an unknown field is None.

    uv [N,2] float32: texture coordinates (v = 0 is an image's top row).
    footprint [N,4] float32: (du/dx, dv/dx, du/dy, dv/dy), how uv changes
    from one pixel to the next; zeros for a point lookup.
    position [N,3] float32: world space, scene units; None where no point
    of the batch lies on a parameterised surface (spheres, meshes with uvs),
    0 at the points without one in a batch where others have one.
    shape, primitive [N] uint32: the scene's shape each point lies on
    (MISS, 0xFFFFFFFF: none, e.g. a point light) and its triangle;
    barycentrics [N,2] float32: (b1, b2) of that triangle's second and third
    corners. None, all three, when the caller has no scene.
    attributes: each name of ``Texture.attributes()`` to its values [N,3]
    float32 (a one-channel attribute in all three); 0 on shapes without it
    and everywhere when the caller has no scene.
    """

    uv: np.ndarray
    footprint: np.ndarray
    position: np.ndarray | None = None
    shape: np.ndarray | None = None
    primitive: np.ndarray | None = None
    barycentrics: np.ndarray | None = None
    # Read-only by default: the default is shared by every instance.
    attributes: Mapping[str, np.ndarray] = MappingProxyType({})


class Texture(Component):
    """A float (1 channel) or RGB (3 channels) texture, evaluated in batches."""

    interface_name = "yarf.v1.Texture"

    @abc.abstractmethod
    def channels(self) -> int:
        """1 (a float texture) or 3 (RGB); fixed for an instance."""

    def attributes(self) -> list[str]:
        """Mesh attributes ("vertex_NAME", "face_NAME") evaluate reads; fixed for an instance."""
        return []

    @abc.abstractmethod
    def evaluate(self, at: SurfacePoints) -> np.ndarray:
        """[N, channels()] values at the points, filtered over their footprint."""

    @abc.abstractmethod
    def mean(self) -> np.ndarray:
        """The mean over the unit square of uv: channels() values."""
