"""Lambertian surface models that fail on purpose, for the fault-isolation
tests: each misbehaves in one way a component in another process can."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
from yarf_component import ScatterFlags, TransportMode
from yarf_component.loading import load_target

EXAMPLES = Path(__file__).resolve().parents[2] / "components" / "python" / "examples"
(Lambertian,) = load_target(f"{EXAMPLES / 'lambertian.py'}:Lambertian")

Sampled = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


class FaultAfter(Lambertian):  # type: ignore[misc, valid-type]
    """A Lambertian whose Sample misbehaves from call number ``after`` + 1 on."""

    def __init__(
        self, reflectance: tuple[float, float, float] = (0.5, 0.5, 0.5), after: int = 0
    ) -> None:
        super().__init__(reflectance)
        self.after = after
        self.calls = 0

    def sample(
        self,
        wi: np.ndarray,
        uv: np.ndarray,
        uniform: np.ndarray,
        allowed: ScatterFlags,
        mode: TransportMode,
    ) -> Sampled:
        self.calls += 1
        sampled = super().sample(wi, uv, uniform, allowed, mode)
        return self.fault(sampled) if self.calls > self.after else sampled

    def fault(self, sampled: Sampled) -> Sampled:
        raise NotImplementedError


class Crashing(FaultAfter):
    """The process dies mid-call; with ``marker``, only while that file is absent
    (it is created first), so a restarted process behaves."""

    class_name = "crashing_lambertian"

    def __init__(
        self,
        reflectance: tuple[float, float, float] = (0.5, 0.5, 0.5),
        after: int = 0,
        marker: str = "",
    ) -> None:
        super().__init__(reflectance, after)
        self.marker = Path(marker) if marker else None

    def fault(self, sampled: Sampled) -> Sampled:
        if self.marker is not None:
            if self.marker.exists():
                return sampled
            self.marker.touch()
        os._exit(3)


class Hanging(FaultAfter):
    """Never answers."""

    class_name = "hanging_lambertian"

    def fault(self, sampled: Sampled) -> Sampled:
        time.sleep(3600)
        return sampled


class WrongLength(FaultAfter):
    """Answers one query too few."""

    class_name = "short_lambertian"

    def fault(self, sampled: Sampled) -> Sampled:
        wo, weight, pdf, flags = sampled
        return wo[:-1], weight[:-1], pdf[:-1], flags[:-1]


class NotANumber(FaultAfter):
    """Puts a NaN in the weights."""

    class_name = "nan_lambertian"

    def fault(self, sampled: Sampled) -> Sampled:
        wo, weight, pdf, flags = sampled
        weight = weight.copy()
        weight[0, 0] = np.nan
        return wo, weight, pdf, flags


class NegativePdf(FaultAfter):
    """Claims a negative density."""

    class_name = "negative_pdf_lambertian"

    def fault(self, sampled: Sampled) -> Sampled:
        wo, weight, pdf, flags = sampled
        return wo, weight, -np.abs(pdf) - 1, flags
