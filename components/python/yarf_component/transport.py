"""The Transport interface (transport.proto): light transport over primary sample space."""

from __future__ import annotations

import abc

import numpy as np

from yarf_component.component import Component
from yarf_component.scene_view import SceneView

# Coordinates of a point of primary sample space the camera reads: film x,
# y, lens u, v, shutter; 5 is unused; a transport's own start at 6.
FILM, LENS, TIME, FIRST_FREE = 0, 2, 4, 6

TransportResult = tuple[np.ndarray, bool] | tuple[np.ndarray, bool, np.ndarray]


class Transport(Component):
    """A light transport algorithm: points of [0,1)^d to film contributions.

    ``scene`` is the job's scene on the yarfd that called (see SceneView).
    """

    interface_name = "yarf.v1.Transport"

    @abc.abstractmethod
    def dimensions(self) -> int:
        """d: coordinates per point, at least 6; fixed for an instance."""

    def prepare(self, scene: SceneView) -> None:
        """Once per job, before any ``evaluate``: caches, photon maps..."""

    @abc.abstractmethod
    def evaluate(self, scene: SceneView, points: np.ndarray) -> TransportResult:
        """Film contributions of points [N, d].

        Returns contributions [M, 5] (raster x, y in pixels, then RGB) and
        ``splats``: False for camera samples (averaged per pixel), True for
        paths from the lights (summed). Optionally a third array, uint32 [M],
        the point each contribution came from (when M != N or rows are
        reordered).
        """
