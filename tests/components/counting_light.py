"""py_area_light that keeps count of its calls: each Radiance call adds a
line (the rows it was asked for) to the file its ``log`` property names,
for the tests of how often a transport calls an emitter in another
process."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from yarf_component import Rgb
from yarf_component.loading import load_target

EXAMPLES = Path(__file__).resolve().parents[2] / "components" / "python" / "examples"
(AreaLight,) = load_target(f"{EXAMPLES / 'area_light.py'}:AreaLight")


class CountingLight(AreaLight):  # type: ignore[misc, valid-type]
    class_name = "py_counting_light"
    summary = "py_area_light that logs each Radiance call"

    def __init__(self, radiance: Rgb, log: str) -> None:
        super().__init__(radiance)
        self.log = Path(log)

    def radiance(self, w: np.ndarray, uv: np.ndarray) -> np.ndarray:
        with self.log.open("a", encoding="utf-8") as out:
            out.write(f"{len(w)}\n")
        return super().radiance(w, uv)
