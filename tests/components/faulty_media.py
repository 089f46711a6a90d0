"""Homogeneous media that fail on purpose, for the fault-isolation tests of
Remote<Medium>: each misbehaves in one way a medium in another process can."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
from yarf_component.loading import load_target

EXAMPLES = Path(__file__).resolve().parents[2] / "components" / "python" / "examples"
(Homogeneous,) = load_target(f"{EXAMPLES / 'homogeneous.py'}:Homogeneous")

Coefficients = tuple[np.ndarray, np.ndarray, np.ndarray]
Segments = tuple[np.ndarray, np.ndarray]


class FaultyCoefficients(Homogeneous):  # type: ignore[misc, valid-type]
    """A homogeneous medium whose coefficients misbehave."""

    def coefficients(self, position: np.ndarray) -> Coefficients:
        return self.fault(super().coefficients(position))

    def fault(self, coefficients: Coefficients) -> Coefficients:
        raise NotImplementedError


class Crashing(FaultyCoefficients):
    """The process dies mid-call."""

    class_name = "crashing_medium"

    def fault(self, coefficients: Coefficients) -> Coefficients:
        os._exit(3)


class Hanging(FaultyCoefficients):
    """Never answers."""

    class_name = "hanging_medium"

    def fault(self, coefficients: Coefficients) -> Coefficients:
        time.sleep(3600)
        return coefficients


class WrongLength(FaultyCoefficients):
    """Answers one point too few."""

    class_name = "short_medium"

    def fault(self, coefficients: Coefficients) -> Coefficients:
        return tuple(c[:-1] for c in coefficients)  # type: ignore[return-value]


class NotANumber(FaultyCoefficients):
    """Puts a NaN in the scattering coefficients."""

    class_name = "nan_medium"

    def fault(self, coefficients: Coefficients) -> Coefficients:
        sigma_a, sigma_s, emission = coefficients
        sigma_s = sigma_s.copy()
        sigma_s[0, 1] = np.nan
        return sigma_a, sigma_s, emission


class NegativeAbsorption(FaultyCoefficients):
    """Claims a negative absorption coefficient."""

    class_name = "negative_medium"

    def fault(self, coefficients: Coefficients) -> Coefficients:
        sigma_a, sigma_s, emission = coefficients
        return -np.abs(sigma_a) - 1, sigma_s, emission


class SegmentsPastTheRay(Homogeneous):  # type: ignore[misc, valid-type]
    """Majorant segments that run past the end of their rays."""

    class_name = "overlong_medium"

    def majorants(self, origin: np.ndarray, direction: np.ndarray, tmax: np.ndarray) -> Segments:
        segments, offsets = super().majorants(origin, direction, tmax)
        segments[:, 1] += 1
        return segments, offsets


class GarbageOffsets(Homogeneous):  # type: ignore[misc, valid-type]
    """Segment offsets of the wrong dtype and length."""

    class_name = "garbage_offsets_medium"

    def majorants(self, origin: np.ndarray, direction: np.ndarray, tmax: np.ndarray) -> Segments:
        segments, offsets = super().majorants(origin, direction, tmax)
        return segments, offsets[1:].astype(np.float32)
