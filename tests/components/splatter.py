"""A transport that only splats, through the job's film splat call: every
point adds 1/(W·H) at the centre of the middle pixel, so one pass of W×H
points adds 1 there."""

from __future__ import annotations

import numpy as np
from yarf_component import JobScene, Transport
from yarf_component.transport import FIRST_FREE


class CentreSplatter(Transport):
    class_name = "centre_splatter"
    summary = "Splats a known amount of light into the middle pixel"

    def dimensions(self) -> int:
        return FIRST_FREE

    def evaluate(self, scene: JobScene, points: np.ndarray) -> tuple[np.ndarray, bool]:
        width, height = scene.layout.width, scene.layout.height
        value = 1.0 / (width * height)
        row = [width // 2 + 0.5, height // 2 + 0.5, value, value, value]
        scene.splat(np.tile(np.array(row, np.float32), (len(points), 1)))
        return np.zeros((0, 5), np.float32), True
