"""py_vegas: Lepage's VEGAS, adaptive importance-sampling Monte Carlo, as a Python Integrator.

A map x(y) from the unit cube onto the box is built one axis at a time:
along each axis [0, 1) is cut into ``bins`` equal steps in y, and step i
is stretched linearly onto [x_i, x_{i+1}], so ∫ f dx = ∫ J(y) f(x(y)) dy
with J = Π_axes bins · (x_{i+1} - x_i). Each iteration estimates the
integral by plain Monte Carlo in y (the mean of J f, its variance over the
points divided by their number), then adapts the grid to the first
output of f: bin i of an axis collects the mean of (J f)² over its points,
smoothed with its neighbours (1:6:1), normalised to r_i and damped to
((1 - r_i) / ln(1/r_i))^alpha, and the edges move so that every bin holds
an equal share. Bins shrink where |f| is large.

Iterations are combined weighted by the inverse variance of the first
output, the one the grid follows, every output with the same weights (a
single output as Lepage does): an output weighted by its own variance
estimate would weigh each iteration by how low it happened to come out,
as the two rise together, and its mean comes out low when it has few
points per iteration, as one pixel of a tile has when yarfd renders
through this integrator. Each output gets Lepage's χ²/dof of the
iterations about its mean and Q, the chance of a χ² that large if their
errors are right (Q < 0.05: the errors are not to be trusted); the first
``discard`` only train the grid. Each iteration spends an equal part of
the budget, at least 4096 points (fewer iterations run when the budget is
small), and f is called with batches of 4096 to 16384 points. Points come
from the caller's sampler, else from numpy's PCG64 seeded with the
request's seed, so a result is a function of the seed.

Properties:
    iterations   int, default 10    adaptation iterations, ≥ 1
    bins         int, default 50    grid bins per axis, ≥ 2
    alpha        float, default 0.5 damping of the refinement, ≥ 0 (Lepage's
                                    default); 0 freezes the grid (plain Monte Carlo)
    discard      int, default 2     leading iterations left out of the result
                                    (at most iterations - 1)
"""

from __future__ import annotations

import math

import numpy as np

from yarf_component import Integrand, Integrator, PointSource

MIN_POINTS_PER_CALL = 4096
MAX_POINTS_PER_CALL = 16384


class AdaptiveMap:
    """The separable piecewise-linear map y -> x of a box, one row of edges per axis."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray, bins: int) -> None:
        steps = np.linspace(0.0, 1.0, bins + 1)
        self.bins = bins
        self.edges = lower[:, None] + (upper - lower)[:, None] * steps[None, :]

    def map(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """x [N, d], the Jacobian [N] and each point's bin per axis [N, d] for y [N, d]."""
        scaled = y * self.bins
        bin_index = np.minimum(scaled.astype(np.int64), self.bins - 1)
        fraction = scaled - bin_index
        axes = np.arange(y.shape[1])[None, :]
        left = self.edges[axes, bin_index]
        width = self.edges[axes, bin_index + 1] - left
        x = left + fraction * width
        jacobian = np.prod(width * self.bins, axis=1)
        return x, jacobian, bin_index

    def refine(self, bin_index: np.ndarray, jf: np.ndarray, alpha: float) -> None:
        """Moves the edges toward where (J f)² is large (see the module's docstring)."""
        if alpha <= 0:
            return
        squares = jf * jf
        for axis in range(self.edges.shape[0]):
            sums = np.bincount(bin_index[:, axis], weights=squares, minlength=self.bins)
            counts = np.bincount(bin_index[:, axis], minlength=self.bins)
            d = np.divide(sums, counts, out=np.zeros(self.bins), where=counts > 0)
            smoothed = np.empty_like(d)
            smoothed[1:-1] = (d[:-2] + 6 * d[1:-1] + d[2:]) / 8
            smoothed[0] = (7 * d[0] + d[1]) / 8
            smoothed[-1] = (d[-2] + 7 * d[-1]) / 8
            total = smoothed.sum()
            if not total > 0 or not np.isfinite(total):
                continue
            r = smoothed / total
            with np.errstate(divide="ignore", invalid="ignore"):
                w = np.where(
                    (r > 0) & (r < 1),
                    ((1 - r) / np.log(1 / r)) ** alpha,
                    np.where(r >= 1, 1.0, 0.0),
                )
            if not w.sum() > 0:
                continue
            # Equal shares of Σ w, the weight spread evenly inside each old bin.
            cumulative = np.concatenate([[0.0], np.cumsum(w)])
            targets = cumulative[-1] * np.arange(1, self.bins) / self.bins
            inner = np.interp(targets, cumulative, self.edges[axis])
            self.edges[axis, 1:-1] = inner


def combine(
    estimates: list[np.ndarray], variances: list[np.ndarray]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The iterations' weighted mean, its error, χ²/dof and Q, per output, every
    output weighted as the first (see the module's docstring)."""
    estimate = np.stack(estimates)
    variance = np.stack(variances)
    guide = variance[:, 0]
    # An iteration whose first output has no variance (f constant along the
    # map) is exact: then the exact iterations alone count, equally.
    exact = guide <= 0
    weight = exact.astype(np.float64) if exact.any() else 1 / guide
    total = weight.sum()
    mean = (weight[:, None] * estimate).sum(axis=0) / total
    error = np.sqrt((weight[:, None] ** 2 * variance).sum(axis=0)) / total
    dof = len(estimates) - 1
    if dof < 1:
        nan = np.full_like(mean, np.nan)
        return mean, error, nan, nan
    # Each output's χ² about its mean by its own errors; an iteration
    # without error says nothing.
    with np.errstate(divide="ignore", invalid="ignore"):
        terms = np.where(variance > 0, (estimate - mean) ** 2 / variance, 0.0)
    chi2 = terms.sum(axis=0)
    q = np.array([chi_square_q(float(c), dof) for c in chi2])
    return mean, error, chi2 / dof, q


def chi_square_q(chi2: float, dof: int) -> float:
    """P(χ² ≥ chi2) for ``dof`` ≥ 1 degrees of freedom, by the closed forms for integer dof."""
    x = chi2 / 2
    if dof % 2 == 0:  # e^-x Σ_{i < dof/2} x^i / i!
        term = total = 1.0
        for i in range(1, dof // 2):
            term *= x / i
            total += term
        return math.exp(-x) * total
    # erfc(√x) + e^-x Σ_{i=1}^{(dof-1)/2} x^(i-1/2) / Γ(i + 1/2)
    total = math.erfc(math.sqrt(x))
    term = math.sqrt(x) / math.gamma(1.5)
    for i in range(1, (dof + 1) // 2):
        total += math.exp(-x) * term
        term *= x / (i + 0.5)
    return total


def split(total: int, parts: int) -> list[int]:
    """``total`` in ``parts`` near-equal parts, the remainder to the first ones."""
    return [total // parts + (1 if k < total % parts else 0) for k in range(parts)]


class Vegas(Integrator):
    class_name = "py_vegas"
    summary = "VEGAS adaptive Monte Carlo (Lepage 1978), in Python"

    def __init__(
        self, iterations: int = 10, bins: int = 50, alpha: float = 0.5, discard: int = 2
    ) -> None:
        if iterations < 1:
            raise ValueError("property 'iterations' must be ≥ 1")
        if bins < 2:
            raise ValueError("property 'bins' must be ≥ 2")
        if not alpha >= 0:
            raise ValueError("property 'alpha' must be ≥ 0")
        if discard < 0:
            raise ValueError("property 'discard' must be ≥ 0")
        self.iterations = iterations
        self.bins = bins
        self.alpha = alpha
        self.discard = discard

    def integrate(
        self,
        f: Integrand,
        lower: np.ndarray,
        upper: np.ndarray,
        evaluations: int,
        seed: int,
        sampler: PointSource | None,
    ) -> tuple[np.ndarray, np.ndarray, int, np.ndarray, np.ndarray]:
        d = len(lower)
        iterations = max(1, min(self.iterations, evaluations // MIN_POINTS_PER_CALL))
        discard = min(self.discard, iterations - 1)
        grid = AdaptiveMap(lower, upper, self.bins)
        rng = np.random.default_rng(seed)
        spent = 0
        estimates: list[np.ndarray] = []
        variances: list[np.ndarray] = []
        for iteration, points in enumerate(split(evaluations, iterations)):
            calls = max(1, -(-points // MAX_POINTS_PER_CALL))
            jf_parts = []
            bin_parts = []
            for batch in split(points, calls):
                if sampler is not None:
                    y = sampler(spent, batch, d).astype(np.float64)
                else:
                    y = rng.random((batch, d))
                spent += batch
                x, jacobian, bin_index = grid.map(y)
                jf_parts.append(jacobian[:, None] * f(x))
                bin_parts.append(bin_index)
            jf = np.concatenate(jf_parts)
            if iteration >= discard:
                estimates.append(jf.mean(axis=0))
                variances.append(jf.var(axis=0, ddof=1) / len(jf) if len(jf) > 1 else jf[0] * 0)
            grid.refine(np.concatenate(bin_parts), jf[:, 0], self.alpha)
        estimate, error, chi2_per_dof, q = combine(estimates, variances)
        return estimate, error, spent, chi2_per_dof, q
