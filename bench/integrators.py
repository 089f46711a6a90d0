"""Integrators at equal evaluations: yarf's against Lepage's `vegas` package.

For each integrand (known closed form) and method, the RMS relative error
over several seeds at the same number of function evaluations. yarf's
integrators run in yarfd and call the integrand, served from this process,
in batches; Lepage's runs here on the same numpy function. Prints a table
and the ratio of yarf's vegas+ error to Lepage's; results also go to
out/bench/integrators.json.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import vegas

from yarf import integrate
from yarf.server import LocalServer

ROOT = Path(__file__).resolve().parent.parent
EVALUATIONS = int(os.environ.get("YARF_BENCH_EVALUATIONS", "100000"))
SEEDS = range(int(os.environ.get("YARF_BENCH_INTEGRATOR_SEEDS", "5")))
METHODS = ("mean_sample", "rqmc", "miser", "vegas", "vegas+")


@dataclass(frozen=True)
class Integrand:
    name: str
    dimensions: int
    f: Callable[[np.ndarray], np.ndarray]
    exact: float


def gaussian_peak(d: int, centre: float, width: float) -> Integrand:
    def f(x: np.ndarray) -> np.ndarray:
        return np.exp(-np.sum((x - centre) ** 2, axis=1) / (2 * width**2))

    one = (
        width
        * math.sqrt(math.pi / 2)
        * (
            math.erf((1 - centre) / (width * math.sqrt(2)))
            + math.erf(centre / (width * math.sqrt(2)))
        )
    )
    return Integrand(f"gaussian peak d={d} w={width}", d, f, one**d)


def double_peak(d: int, width: float) -> Integrand:
    a, b = gaussian_peak(d, 0.33, width), gaussian_peak(d, 0.67, width)
    return Integrand(
        f"double peak d={d} w={width}", d, lambda x: a.f(x) + b.f(x), a.exact + b.exact
    )


def oscillatory(d: int) -> Integrand:
    # Genz oscillatory: cos(2π u + Σ a_i x_i), ∫ = Re(e^{i2πu} Π (e^{i a_i} − 1)/(i a_i)).
    a, u = np.linspace(0.5, 1.5, d), 0.3

    def f(x: np.ndarray) -> np.ndarray:
        return np.cos(2 * np.pi * u + x @ a)

    value = np.exp(2j * np.pi * u) * np.prod((np.exp(1j * a) - 1) / (1j * a))
    return Integrand(f"genz oscillatory d={d}", d, f, float(value.real))


def corner_peak(d: int) -> Integrand:
    # Genz corner peak with a_i = 1: (1 + Σ x_i)^{-(d+1)}; ∫ by inclusion–exclusion.
    def f(x: np.ndarray) -> np.ndarray:
        return (1 + np.sum(x, axis=1)) ** (-(d + 1))

    exact = sum((-1) ** k * math.comb(d, k) / (1 + k) for k in range(d + 1)) / math.factorial(d)
    return Integrand(f"genz corner peak d={d}", d, f, exact)


INTEGRANDS = (
    gaussian_peak(4, 0.4, 0.05),
    double_peak(4, 0.05),
    oscillatory(6),
    corner_peak(3),
)


def lepage(integrand: Integrand, seed: int) -> float:
    np.random.seed(seed)
    integrator = vegas.Integrator([[0, 1]] * integrand.dimensions)
    iterations = 10
    f = vegas.lbatchintegrand(integrand.f)
    integrator(f, nitn=2, neval=EVALUATIONS // iterations)  # adapt, as yarf discards two
    return float(integrator(f, nitn=iterations - 2, neval=EVALUATIONS // iterations).mean)


def yarf(integrand: Integrand, method: str, seed: int, address: str) -> float:
    zero, one = [0.0] * integrand.dimensions, [1.0] * integrand.dimensions
    result = integrate(
        integrand.f,
        zero,
        one,
        method=method,
        evaluations=EVALUATIONS,
        seed=seed,
        server=address,
    )
    return float(result.estimate[0])


def rms_relative_error(estimates: list[float], exact: float) -> float:
    return float(np.sqrt(np.mean([((e - exact) / exact) ** 2 for e in estimates])))


def main() -> None:
    table: dict[str, dict[str, float]] = {}
    with LocalServer() as server:
        for integrand in INTEGRANDS:
            row = {
                method: rms_relative_error(
                    [yarf(integrand, method, seed, server.address) for seed in SEEDS],
                    integrand.exact,
                )
                for method in METHODS
            }
            row["lepage vegas"] = rms_relative_error(
                [lepage(integrand, seed) for seed in SEEDS], integrand.exact
            )
            table[integrand.name] = row
    columns = (*METHODS, "lepage vegas")
    print(f"RMS relative error at {EVALUATIONS} evaluations over {len(SEEDS)} seeds")
    print(f"{'integrand':<28}" + "".join(f"{c:>14}" for c in columns))
    for name, row in table.items():
        print(f"{name:<28}" + "".join(f"{row[c]:>14.2e}" for c in columns))
    ratios = {name: row["vegas+"] / row["lepage vegas"] for name, row in table.items()}
    for name, ratio in ratios.items():
        print(f"ratio yarf vegas+ / lepage vegas, {name}: {ratio:.2f}")
    out = ROOT / "out" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "integrators.json").write_text(json.dumps({"errors": table, "ratios": ratios}, indent=2))
    print("ratios " + json.dumps(ratios))


if __name__ == "__main__":
    main()
