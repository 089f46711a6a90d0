"""yarf.integrate: a numpy function served from this process, integrated by
the server's C++ integrators, which call it back in batches."""

from __future__ import annotations

import grpc
import numpy as np
import pytest

from yarf import Client, IntegrationWarning, integrate
from yarf.integrate import DEFAULT_SAMPLERS, LEPAGE_OPTIONS


def test_mean_sample_integrates_a_polynomial_within_its_error_bar(client: Client) -> None:
    calls: list[int] = []

    def f(x: np.ndarray) -> np.ndarray:
        calls.append(x.shape[0])
        return x[:, 0] ** 2 * x[:, 1] + x[:, 2]

    result = integrate(
        f, [0, 0, -1], [1, 2, 1], method="mean_sample", evaluations=20_000, seed=3, server=client
    )
    exact = 4.0 / 3.0  # ∫ x² y = (1/3)(2)(2); ∫ z over [-1, 1] vanishes
    assert result.evaluations == 20_000
    assert abs(result.estimate[0] - exact) < 4 * result.standard_error[0]
    assert 0 < result.standard_error[0] < 0.05
    # The server calls back in batches, not per point (the first call is our probe).
    assert max(calls) >= 4096 and len(calls) <= 10


def test_sobol_points_make_the_error_far_smaller(client: Client) -> None:
    def f(x: np.ndarray) -> np.ndarray:
        return np.exp(-np.sum(x**2, axis=1))

    exact = (np.sqrt(np.pi) / 2 * 0.8427007929497149) ** 2  # ∫_0^1 e^{-t²} dt, squared
    errors = {}
    for sampler in ("independent", "sobol"):
        result = integrate(
            f,
            [0, 0],
            [1, 1],
            method="mean_sample",
            sampler=sampler,
            evaluations=4096,
            server=client,
        )
        errors[sampler] = abs(result.estimate[0] - exact)
    assert errors["sobol"] < errors["independent"] / 5


def test_vector_valued_functions_give_one_estimate_per_output(client: Client) -> None:
    result = integrate(
        lambda x: np.stack([np.ones(len(x)), x[:, 0]], axis=1),
        [0],
        [2],
        method="mean_sample",
        evaluations=8192,
        server=client,
    )
    assert result.estimate.shape == (2,)
    assert result.estimate[0] == pytest.approx(2.0, abs=1e-5)
    assert result.estimate[1] == pytest.approx(2.0, abs=4 * result.standard_error[1])


def test_a_failing_function_fails_the_call_with_its_own_message(client: Client) -> None:
    def broken(x: np.ndarray) -> np.ndarray:
        if len(x) > 1:
            raise ZeroDivisionError("the integrand divided by zero")
        return x[:, 0]

    with pytest.raises(grpc.RpcError) as failure:
        integrate(broken, [0], [1], method="mean_sample", evaluations=1000, server=client)
    assert "the integrand divided by zero" in failure.value.details()
    assert "remote Function 0 at" in failure.value.details()

    def wrong_length(x: np.ndarray) -> np.ndarray:
        return np.zeros(max(1, len(x) // 2)) if len(x) > 1 else np.zeros(1)

    with pytest.raises(grpc.RpcError) as short:
        integrate(wrong_length, [0], [1], method="mean_sample", evaluations=1000, server=client)
    assert "shape" in short.value.details()
    # The server is still there.
    assert client.is_serving()


def test_values_float32_cannot_hold_are_refused_not_changed(client: Client) -> None:
    """The server integrates float32 values: a complex value lost its
    imaginary part and 1e39 became inf, silently."""
    with pytest.raises(TypeError, match="complex values"):
        integrate(lambda x: np.exp(1j * x[:, 0]), [0], [1], evaluations=1000, server=client)

    def huge_near_one(x: np.ndarray) -> np.ndarray:
        return np.where(x[:, 0] > 0.9, 1e39, 1.0)

    with pytest.raises(grpc.RpcError) as beyond:
        integrate(huge_near_one, [0], [1], method="mean_sample", evaluations=1000, server=client)
    assert "beyond float32's range" in beyond.value.details()
    with pytest.raises(TypeError, match="not numbers"):
        integrate(lambda x: np.array(["a"] * len(x)), [0], [1], evaluations=1000, server=client)


def test_vegas_plus_finds_a_narrow_peak_that_mean_sample_misses(client: Client) -> None:
    centre, width = 0.3, 0.02

    def peak(x: np.ndarray) -> np.ndarray:
        return np.exp(-np.sum((x - centre) ** 2, axis=1) / (2 * width**2))

    exact = (width * np.sqrt(2 * np.pi)) ** 3  # the peak lies well inside the cube
    vegas = integrate(peak, [0] * 3, [1] * 3, method="vegas+", evaluations=100_000, server=client)
    plain = integrate(
        peak, [0] * 3, [1] * 3, method="mean_sample", evaluations=100_000, server=client
    )
    assert abs(vegas.estimate[0] - exact) < 4 * vegas.standard_error[0]
    assert abs(vegas.estimate[0] - exact) < 0.02 * exact
    assert vegas.standard_error[0] < plain.standard_error[0] / 10


def test_vegas_reports_chi_square_and_q_and_one_shot_methods_do_not(client: Client) -> None:
    def f(x: np.ndarray) -> np.ndarray:
        peak = np.exp(-np.sum((x - 0.4) ** 2, axis=1) * 20)
        return np.stack([peak, peak * x[:, 0]], axis=1)

    vegas = integrate(f, [0, 0], [1, 1], method="vegas", evaluations=20_000, seed=1, server=client)
    assert vegas.chi2_per_dof.shape == vegas.q.shape == (2,)
    assert np.all(vegas.chi2_per_dof >= 0) and np.all((vegas.q >= 0) & (vegas.q <= 1))
    text = str(vegas)
    assert "χ²/dof" in text and "Q = " in text
    assert "q=" in repr(vegas) and "chi2_per_dof=" in repr(vegas)
    plain = integrate(f, [0, 0], [1, 1], method="mean_sample", evaluations=20_000, server=client)
    assert np.all(np.isnan(plain.chi2_per_dof)) and np.all(np.isnan(plain.q))
    assert plain.trustworthy and "Q = " not in str(plain)


def test_iterations_that_disagree_give_a_small_q_and_a_warning(client: Client) -> None:
    calls = [0]

    def drifting(x: np.ndarray) -> np.ndarray:
        # Each call (one per iteration here) is shifted: the iterations
        # disagree far beyond their errors.
        calls[0] += 1
        return x[:, 0] + 0.05 * calls[0]

    with pytest.warns(IntegrationWarning, match="Q = "):
        result = integrate(
            drifting, [0], [1], method="vegas", evaluations=10_000, seed=2, server=client
        )
    assert result.q[0] < 0.05 and not result.trustworthy
    assert "not to be trusted" in str(result)


def test_lepage_option_names_map_onto_yarfs(client: Client) -> None:
    assert LEPAGE_OPTIONS["nitn"] == "iterations"
    sizes: list[int] = []

    def f(x: np.ndarray) -> np.ndarray:
        sizes.append(len(x))
        return np.exp(-np.sum((x - 0.5) ** 2, axis=1))

    result = integrate(
        f, [0, 0], [1, 1], method="vegas+", nitn=5, neval=3000, alpha=0.7, beta=0.5, server=client
    )
    # neval is per iteration: 5 iterations of 3000 points, one call each
    # after the probe of the function's shape.
    assert result.evaluations == 15_000
    assert sizes[1:] == [3000] * 5
    with pytest.raises(ValueError, match="neval"):
        integrate(f, [0], [1], neval=1000, evaluations=5000, server=client)
    with pytest.raises(ValueError, match="twice"):
        integrate(f, [0], [1], nitn=5, iterations=6, server=client)


@pytest.mark.parametrize(
    "method",
    [
        "mean_sample",
        "stratified_mc",
        "rqmc",
        "miser",
        "simpson",
        "vegas",
        "vegas+",
        "control_variate",
        "adaptive_hierarchical",
    ],
)
def test_evaluations_never_exceed_the_budget(client: Client, method: str) -> None:
    seen = [0]

    def f(x: np.ndarray) -> np.ndarray:
        seen[0] += len(x)
        return np.cos(x[:, 0] + 2 * x[:, 1])

    for budget in (1_000, 12_345, 40_001):
        seen[0] = 0
        result = integrate(f, [0, 0], [1, 1], method=method, evaluations=budget, server=client)
        spent = seen[0] - 1  # the probe of the function's shape
        assert spent <= budget, (method, budget, spent)
        assert result.evaluations == spent, (method, budget)


def test_rqmc_takes_scrambled_sobol_points_by_default() -> None:
    assert DEFAULT_SAMPLERS["rqmc"] == "sobol_nd"
