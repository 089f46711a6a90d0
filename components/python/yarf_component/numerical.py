"""Numerical interfaces (math.proto): Function, Sampler, Generator, Warp, RootFinder, Integrator.

Points travel as float32 arrays [N, d], one row per point.
"""

from __future__ import annotations

import abc
from collections.abc import Callable, Sequence

import numpy as np

from yarf_component.component import Component

# f: points [N, d] -> values [N, k], as an Integrator receives its integrand.
Integrand = Callable[[np.ndarray], np.ndarray]
# (first_index, count, dimensions) -> points [count, dimensions] in [0,1).
PointSource = Callable[[int, int, int], np.ndarray]
Values = Sequence[float] | np.ndarray
# What Integrator.integrate returns: (estimate, standard error, evaluations),
# optionally followed by (χ²/dof, Q), each [k].
IntegratorAnswer = tuple[Values, Values, int] | tuple[Values, Values, int, Values, Values]


class Function(Component):
    """A vector-valued function R^d -> R^k evaluated on batches of points.

    Set ``input_dimensions`` (d) and ``output_dimensions`` (k), as class
    attributes or in ``__init__``.
    """

    interface_name = "yarf.v1.Function"
    input_dimensions: int
    output_dimensions: int

    @abc.abstractmethod
    def evaluate(self, points: np.ndarray) -> np.ndarray:
        """[N, k]: f at each row of points [N, d]."""


class Sampler(Component):
    """Point sets in [0,1)^d addressed by index: the same request gives the same points."""

    interface_name = "yarf.v1.Sampler"

    @abc.abstractmethod
    def generate(self, first_index: int, count: int, dimensions: int, seed: int) -> np.ndarray:
        """[count, dimensions]: points first_index .. first_index+count-1 of seed's sequence."""


class Generator(Component):
    """Streams of uniform numbers in [0,1), addressed by (seed, stream, offset): stateless."""

    interface_name = "yarf.v1.Generator"

    @abc.abstractmethod
    def next(self, seed: int, stream: int, offset: int, count: int) -> np.ndarray:
        """[count]: numbers offset .. offset+count-1 of stream ``stream`` of ``seed``."""


class Warp(Component):
    """A map from uniform points of [0,1)^m to an image in R^n, with its density.

    Set ``domain_dimensions`` (m) and ``image_dimensions`` (n).
    """

    interface_name = "yarf.v1.Warp"
    domain_dimensions: int
    image_dimensions: int

    @abc.abstractmethod
    def forward(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Uniform points [N, m] -> warped points [N, n] and their densities [N]."""

    def inverse(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points of the image [N, n] -> preimages [N, m] and densities [N].

        A warp without an inverse leaves this out: callers get UNIMPLEMENTED.
        """
        raise NotImplementedError

    @abc.abstractmethod
    def pdf(self, points: np.ndarray) -> np.ndarray:
        """[N]: the density at points of the image [N, n]; 0 outside the image."""


class NoRoot(Exception):
    """What find_root raises when the bracket holds no sign change or the iteration
    does not converge: the caller gets INVALID_ARGUMENT with the message."""


class RootFinder(Component):
    """Roots of a scalar function of one variable."""

    interface_name = "yarf.v1.RootFinder"

    @abc.abstractmethod
    def find_root(
        self, f: Integrand, lower: float, upper: float, tolerance: float, max_iterations: int
    ) -> tuple[float, int]:
        """x in [lower, upper] with f(x) = 0 to within ``tolerance``, and the iterations spent.

        ``f`` maps points [N, 1] to float64 values [N, k], each call one batch
        to the function's host; column 0 is f (Newton's method reads f' in
        column 1). Raise NoRoot when there is none to find.
        """


class Integrator(Component):
    """Numerical integration of a Function over a box."""

    interface_name = "yarf.v1.Integrator"

    @abc.abstractmethod
    def integrate(
        self,
        f: Integrand,
        lower: np.ndarray,
        upper: np.ndarray,
        evaluations: int,
        seed: int,
        sampler: PointSource | None,
    ) -> IntegratorAnswer:
        """∫ f over [lower, upper] (float64 [d] each) with at most ``evaluations`` points.

        ``f`` maps points [N, d] to float64 values [N, k], each call one batch
        to the function's host; ``sampler`` gives the points of the
        caller's Sampler for ``seed`` (None: draw independent points from
        ``seed``). Returns the estimate [k], its standard error [k] and the
        evaluations spent; an integrator that averages iterations may add
        χ²/dof [k] and Q [k] of its iterations (Lepage's definitions, see
        IntegrateReply in math.proto).
        """
