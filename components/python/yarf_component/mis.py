"""Multiple importance sampling, as the transports written in Python weigh their
strategies."""

from __future__ import annotations

import numpy as np

from yarf_component.surface import ScatterFlags


def power_heuristic(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Veach's power heuristic (β = 2) of strategy a against b."""
    a2, b2 = np.square(a, dtype=np.float64), np.square(b, dtype=np.float64)
    total = a2 + b2
    return np.divide(a2, total, out=np.zeros_like(total), where=total > 0).astype(np.float32)


def samples_lights(lobes: int) -> bool:
    """Whether a light sample can find anything: all but purely specular models."""
    return bool(lobes & (ScatterFlags.DIFFUSE | ScatterFlags.GLOSSY)) or not (
        lobes & ScatterFlags.DELTA
    )
