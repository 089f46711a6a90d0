"""py_bisection: bisection as a Python RootFinder.

Halves the bracket [lower, upper], keeping the half whose ends differ in
sign, until it is no wider than 2·tolerance; the root is its midpoint.
Each iteration is one call of f (one point). f(lower) and f(upper) must
differ in sign (or one be 0). No properties.
"""

from __future__ import annotations

import numpy as np

from yarf_component import Integrand, NoRoot, RootFinder


def value(f: Integrand, x: float) -> float:
    return float(f(np.array([[x]], np.float32))[0, 0])


class Bisection(RootFinder):
    class_name = "py_bisection"
    summary = "Bisection of a bracket with a sign change"

    def find_root(
        self, f: Integrand, lower: float, upper: float, tolerance: float, max_iterations: int
    ) -> tuple[float, int]:
        f_lower, f_upper = value(f, lower), value(f, upper)
        if f_lower == 0:
            return lower, 0
        if f_upper == 0:
            return upper, 0
        if (f_lower < 0) == (f_upper < 0):
            raise NoRoot(f"f has the same sign at {lower} and {upper}")
        for iteration in range(1, max_iterations + 1):
            middle = 0.5 * (lower + upper)
            f_middle = value(f, middle)
            if f_middle == 0 or upper - lower <= 2 * tolerance:
                return middle, iteration
            if (f_middle < 0) == (f_lower < 0):
                lower, f_lower = middle, f_middle
            else:
                upper = middle
        raise NoRoot(f"no convergence to {tolerance} within {max_iterations} iterations")
