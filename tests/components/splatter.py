"""A transport that only splats: every point adds 1/(W·H) at the centre of the
middle pixel, so one pass of W×H points adds 1 there."""

from __future__ import annotations

import numpy as np
from yarf_component import SceneView, Transport
from yarf_component.transport import FIRST_FREE


class CentreSplatter(Transport):
    class_name = "centre_splatter"
    summary = "Splats a known amount of light into the middle pixel"

    def dimensions(self) -> int:
        return FIRST_FREE

    def evaluate(self, scene: SceneView, points: np.ndarray) -> tuple[np.ndarray, bool]:
        width, height = scene.layout.width, scene.layout.height
        value = 1.0 / (width * height)
        row = [width // 2 + 0.5, height // 2 + 0.5, value, value, value]
        return np.tile(np.array(row, np.float32), (len(points), 1)), True
