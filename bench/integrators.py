"""Integrators at equal evaluations: yarf's against the libraries a numerical user has.

Side by side, the mean |relative error| over SEEDS seeds at 10⁴, 10⁵ and 10⁶
evaluations (YARF_BENCH_INTEGRATOR_BUDGETS) of
- yarf's vegas against Lepage's vegas with beta = 0 (his classic
  algorithm), and yarf's vegas_plus against his VEGAS+ (beta = 0.75). Both
  spend the budget as ten iterations: yarf leaves out its first two (its
  default), Lepage's runs two iterations of warm-up in a call of their own
  and reports the other eight;
- yarf's rqmc with its scrambled Sobol sampler (sobol_nd) against scipy's
  scrambled Sobol points (scipy.stats.qmc.Sobol), both as the mean of 10
  independent scramblings of N / 10 points;
and, in each row, plain Monte Carlo (yarf's mean_sample with independent
points) for scale. The integrands are Genz's six test families in
d = 2, 4, 8 and a Gaussian and a double peak after Lepage's (width 1/√200,
d = 4, 8). The ratio yarf / peer of each row and their geometric mean per
method close the table (below 1: yarf's error is smaller).

A second table compares yarf's other integrators on a few integrands (RMS
relative error at 10⁵ evaluations). yarf's integrators run in yarfd and call
the integrand, served from this process, in batches; Lepage's runs here on
the same numpy function. Results also go to out/bench/integrators.json.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from itertools import product
from pathlib import Path

import gvar
import numpy as np
import vegas
from scipy.stats import qmc

from yarf import IntegrationWarning, integrate
from yarf.server import LocalServer

ROOT = Path(__file__).resolve().parent.parent
BUDGETS = tuple(
    int(float(b)) for b in os.environ.get("YARF_BENCH_INTEGRATOR_BUDGETS", "1e4,1e5,1e6").split(",")
)
SEEDS = range(int(os.environ.get("YARF_BENCH_INTEGRATOR_SEEDS", "10")))
ITERATIONS, WARM_UP = 10, 2
SCRAMBLINGS = 10
# yarf's method, and its peer's name.
PEERS = {"vegas": "lepage b=0", "vegas+": "lepage b=.75", "rqmc": "scipy sobol"}
# The second table: yarf's integrators at one budget.
OTHER_EVALUATIONS = 100_000
OTHER_METHODS = (
    "mean_sample",
    "rqmc",
    "miser",
    "vegas",
    "vegas+",
    "control_variate",
    "adaptive_hierarchical",
)


@dataclass(frozen=True)
class Integrand:
    name: str
    dimensions: int
    f: Callable[[np.ndarray], np.ndarray]
    exact: float


def gaussian_peak(d: int, centre: float, width: float) -> Integrand:
    def f(x: np.ndarray) -> np.ndarray:
        return np.exp(-np.sum((x - centre) ** 2, axis=1) / (2 * width**2))

    root2 = width * math.sqrt(2)
    one = (
        width * math.sqrt(math.pi / 2) * (math.erf((1 - centre) / root2) + math.erf(centre / root2))
    )
    return Integrand(f"gaussian peak d={d} w={width:.3g}", d, f, one**d)


def double_peak(d: int, width: float, low: float = 0.33, high: float = 0.67) -> Integrand:
    a, b = gaussian_peak(d, low, width), gaussian_peak(d, high, width)
    return Integrand(
        f"double peak d={d} w={width:.3g}", d, lambda x: a.f(x) + b.f(x), a.exact + b.exact
    )


# Genz's families with their difficulty h = Σ_j a_j, the a_j unequal
# (a_j ∝ j + 1) and the offsets u_j spread over [0.2, 0.8].
GENZ_DIFFICULTY = {
    "oscillatory": 9.0,
    "product peak": 7.25,
    "corner peak": 1.85,
    "gaussian": 7.03,
    "continuous": 20.4,
    "discontinuous": 4.3,
}


def genz(family: str, d: int) -> Integrand:
    weights = np.arange(1.0, d + 1)
    a = GENZ_DIFFICULTY[family] * weights / weights.sum()
    u = 0.2 + 0.6 * (np.arange(d) + 0.5) / d
    f: Callable[[np.ndarray], np.ndarray]
    if family == "oscillatory":

        def f(x: np.ndarray) -> np.ndarray:
            return np.cos(2 * np.pi * u[0] + x @ a)

        exact = (np.exp(2j * np.pi * u[0]) * np.prod((np.exp(1j * a) - 1) / (1j * a))).real
    elif family == "product peak":

        def f(x: np.ndarray) -> np.ndarray:
            return np.prod(1 / (a**-2 + (x - u) ** 2), axis=1)

        exact = np.prod(a * (np.arctan(a * (1 - u)) + np.arctan(a * u)))
    elif family == "corner peak":

        def f(x: np.ndarray) -> np.ndarray:
            return (1 + x @ a) ** (-(d + 1))

        # Inclusion–exclusion over the corners v of the cube.
        total = sum((-1) ** sum(v) / (1 + float(np.dot(a, v))) for v in product((0, 1), repeat=d))
        exact = total / (math.factorial(d) * np.prod(a))
    elif family == "gaussian":

        def f(x: np.ndarray) -> np.ndarray:
            return np.exp(-np.sum((a * (x - u)) ** 2, axis=1))

        erf = np.vectorize(math.erf)
        exact = np.prod(np.sqrt(np.pi) / (2 * a) * (erf(a * (1 - u)) + erf(a * u)))
    elif family == "continuous":

        def f(x: np.ndarray) -> np.ndarray:
            return np.exp(-np.sum(a * np.abs(x - u), axis=1))

        exact = np.prod((2 - np.exp(-a * u) - np.exp(-a * (1 - u))) / a)
    else:  # discontinuous: 0 beyond u on the first two axes

        def f(x: np.ndarray) -> np.ndarray:
            inside = (x[:, 0] <= u[0]) & (x[:, 1] <= u[1])
            return np.where(inside, np.exp(x @ a), 0.0)

        ends = np.where(np.arange(d) < 2, u, 1.0)
        exact = np.prod(np.expm1(a * ends) / a)
    return Integrand(f"genz {family} d={d}", d, f, float(exact))


COMPARED = (
    *(genz(family, d) for family in GENZ_DIFFICULTY for d in (2, 4, 8)),
    *(gaussian_peak(d, 0.5, 1 / math.sqrt(200)) for d in (4, 8)),
    *(double_peak(d, 1 / math.sqrt(200)) for d in (4, 8)),
)
OTHERS = (
    gaussian_peak(4, 0.4, 0.05),
    double_peak(4, 0.05),
    genz("oscillatory", 6),
    genz("corner peak", 3),
)


def peer(integrand: Integrand, method: str, evaluations: int, seed: int) -> float:
    if method == "rqmc":
        return scipy_sobol(integrand, evaluations, seed)
    return lepage(integrand, 0.0 if method == "vegas" else 0.75, evaluations, seed)


def scipy_sobol(integrand: Integrand, evaluations: int, seed: int) -> float:
    n = evaluations // SCRAMBLINGS
    rng = np.random.default_rng(seed)
    means = []
    for _ in range(SCRAMBLINGS):
        sobol = qmc.Sobol(integrand.dimensions, scramble=True, seed=rng)
        with warnings.catch_warnings():  # n is not a power of two at 10⁴ … 10⁶
            warnings.simplefilter("ignore", UserWarning)
            means.append(float(np.mean(integrand.f(sobol.random(n)))))
    return float(np.mean(means))


def lepage(integrand: Integrand, beta: float, evaluations: int, seed: int) -> float:
    gvar.ranseed(seed)
    integrator = vegas.Integrator([[0, 1]] * integrand.dimensions, beta=beta, alpha=0.5)
    f = vegas.lbatchintegrand(integrand.f)
    neval = evaluations // ITERATIONS
    integrator(f, nitn=WARM_UP, neval=neval)
    return float(integrator(f, nitn=ITERATIONS - WARM_UP, neval=neval).mean)


def yarf(integrand: Integrand, method: str, evaluations: int, seed: int, address: str) -> float:
    zero, one = [0.0] * integrand.dimensions, [1.0] * integrand.dimensions
    options = {"replicates": SCRAMBLINGS} if method == "rqmc" else {}
    result = integrate(
        integrand.f,
        zero,
        one,
        method=method,
        evaluations=evaluations,
        seed=seed,
        server=address,
        **options,  # type: ignore[arg-type]
    )
    return float(result.estimate[0])


def mean_relative_error(estimates: list[float], exact: float) -> float:
    return float(np.mean([abs((e - exact) / exact) for e in estimates]))


def rms_relative_error(estimates: list[float], exact: float) -> float:
    return float(np.sqrt(np.mean([((e - exact) / exact) ** 2 for e in estimates])))


def compare(address: str) -> tuple[list[dict[str, object]], dict[str, float]]:
    rows: list[dict[str, object]] = []
    for integrand, evaluations in product(COMPARED, BUDGETS):
        plain = mean_relative_error(
            [yarf(integrand, "mean_sample", evaluations, seed, address) for seed in SEEDS],
            integrand.exact,
        )
        for method in PEERS:
            ours = mean_relative_error(
                [yarf(integrand, method, evaluations, seed, address) for seed in SEEDS],
                integrand.exact,
            )
            theirs = mean_relative_error(
                [peer(integrand, method, evaluations, seed) for seed in SEEDS], integrand.exact
            )
            rows.append(
                {
                    "integrand": integrand.name,
                    "evaluations": evaluations,
                    "method": method,
                    "yarf": ours,
                    "peer": theirs,
                    "ratio": ours / theirs,
                    "plain_mc": plain,
                }
            )
    geometric = {
        method: float(
            np.exp(np.mean([math.log(r["ratio"]) for r in rows if r["method"] == method]))  # type: ignore[arg-type]
        )
        for method in PEERS
    }
    return rows, geometric


def others(address: str) -> dict[str, dict[str, float]]:
    return {
        integrand.name: {
            method: rms_relative_error(
                [yarf(integrand, method, OTHER_EVALUATIONS, seed, address) for seed in SEEDS[:5]],
                integrand.exact,
            )
            for method in OTHER_METHODS
        }
        for integrand in OTHERS
    }


def main() -> None:
    # A small Q is part of what is measured here, not news for every run.
    warnings.simplefilter("ignore", IntegrationWarning)
    with LocalServer() as server:
        rows, geometric = compare(server.address)
        other = others(server.address)
    print(
        f"mean |relative error| over {len(SEEDS)} seeds; yarf against its peer "
        f"(vegas: Lepage's beta=0, vegas+: his beta=0.75, rqmc: scipy's scrambled Sobol, "
        f"{SCRAMBLINGS} scramblings); ratio = yarf / peer; plain MC for scale"
    )
    header = (
        f"{'integrand':<32}{'evals':>9}{'method':>8}{'yarf':>11}{'peer':>11}{'ratio':>8}"
        f"{'plain MC':>11}"
    )
    print(header)
    for r in rows:
        flag = "  >1.5" if r["ratio"] > 1.5 else ""  # type: ignore[operator]
        print(
            f"{r['integrand']:<32}{r['evaluations']:>9}{r['method']:>8}"
            f"{r['yarf']:>11.2e}{r['peer']:>11.2e}{r['ratio']:>8.2f}{r['plain_mc']:>11.2e}{flag}"
        )
    for method, ratio in geometric.items():
        worse = sum(1 for r in rows if r["method"] == method and r["ratio"] > 1.5)  # type: ignore[operator]
        print(
            f"geometric mean ratio yarf {method} / {PEERS[method]}: {ratio:.2f} "
            f"(target <= 0.8); rows worse than 1.5x: {worse}"
        )
    print(f"\nRMS relative error at {OTHER_EVALUATIONS} evaluations over {len(SEEDS[:5])} seeds")
    width = max(len(m) for m in OTHER_METHODS) + 2
    print(f"{'integrand':<32}" + "".join(f"{m:>{width}}" for m in OTHER_METHODS))
    for name, row in other.items():
        print(f"{name:<32}" + "".join(f"{row[m]:>{width}.2e}" for m in OTHER_METHODS))
    out = ROOT / "out" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    report = {"against_peers": rows, "geometric_mean_ratio": geometric, "other_methods": other}
    (out / "integrators.json").write_text(json.dumps(report, indent=2))
    print("ratios " + json.dumps(geometric))


if __name__ == "__main__":
    main()
