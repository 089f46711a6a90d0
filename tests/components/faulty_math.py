"""Numerical components that fail on purpose, for the fault-isolation tests
of Remote<Warp>, Remote<Generator>, Remote<RootFinder> and Remote<Integrator>:
each answers in the one wrong way its ``fault`` property names."""

from __future__ import annotations

import os
import time
from typing import Literal

import numpy as np
from yarf_component import Generator, Integrand, Integrator, PointSource, RootFinder, Warp

Fault = Literal["shape", "nan", "range", "hang", "exit"]
# Well past the tests' one-second deadline, short enough not to hold the
# process's few worker threads for the next test.
HANG_SECONDS = 3.0


class FaultyWarp(Warp):
    """Uniform points of the square, wrong: "shape" drops a row, "nan" a NaN
    point, "range" a negative pdf, "hang" no answer."""

    class_name = "faulty_warp"
    domain_dimensions = 2
    image_dimensions = 2

    def __init__(self, fault: Fault = "shape") -> None:
        self.fault = fault

    def forward(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        image, pdf = points.copy(), np.ones(len(points), np.float32)
        if self.fault == "shape":
            return image[1:], pdf[1:]
        if self.fault == "nan":
            image[0, 0] = np.nan
        if self.fault == "range":
            pdf[0] = -1
        if self.fault == "hang":
            time.sleep(HANG_SECONDS)
        return image, pdf

    def pdf(self, points: np.ndarray) -> np.ndarray:
        return self.forward(points)[1]


class FaultyGenerator(Generator):
    """Numbers of [0,1), wrong: "shape" one too few, "nan" a NaN, "range" a 1."""

    class_name = "faulty_generator"

    def __init__(self, fault: Fault = "range") -> None:
        self.fault = fault

    def next(self, seed: int, stream: int, offset: int, count: int) -> np.ndarray:
        values = np.random.default_rng(seed).random(count, np.float32)
        if self.fault == "shape":
            return values[1:]
        if self.fault == "hang":
            time.sleep(HANG_SECONDS)
        values[-1] = np.nan if self.fault == "nan" else 1.0
        return values


class FaultyRootFinder(RootFinder):
    """Asks f once, then answers wrong: "range" a root past the bracket, "nan" a NaN."""

    class_name = "faulty_root_finder"

    def __init__(self, fault: Fault = "range") -> None:
        self.fault = fault

    def find_root(
        self, f: Integrand, lower: float, upper: float, tolerance: float, max_iterations: int
    ) -> tuple[float, int]:
        f(np.array([[lower]], np.float32))
        if self.fault == "hang":
            time.sleep(HANG_SECONDS)
        return (float("nan") if self.fault == "nan" else upper + 1.0), 1


class FaultyIntegrator(Integrator):
    """Averages f, then answers wrong: "shape" one estimate too many, "nan" a
    NaN estimate, "range" a negative standard error; "exit" answers its
    first call right and ends the whole process in the second (a component
    that dies in the middle of a render)."""

    class_name = "faulty_integrator"

    def __init__(self, fault: Fault = "shape") -> None:
        self.fault = fault
        self.calls = 0

    def integrate(
        self,
        f: Integrand,
        lower: np.ndarray,
        upper: np.ndarray,
        evaluations: int,
        seed: int,
        sampler: PointSource | None,
    ) -> tuple[list[float], list[float], int]:
        self.calls += 1
        if self.fault == "exit" and self.calls > 1:
            os._exit(3)
        points = lower + (upper - lower) * np.random.default_rng(seed).random((64, len(lower)))
        mean = f(points).mean(axis=0).tolist()
        error = [0.1] * len(mean)
        if self.fault == "exit":
            return mean, error, 64
        if self.fault == "shape":
            return [*mean, 0.0], error, 64
        if self.fault == "nan":
            return [float("nan")] * len(mean), error, 64
        if self.fault == "hang":
            time.sleep(HANG_SECONDS)
        return mean, [-0.1] * len(mean), 64
