"""sobol_nd, the Sobol sequence in up to 21201 dimensions with Joe & Kuo's
direction numbers, against scipy's Sobol points: the same sequence
unscrambled, as small an integration error as scipy's scrambled Sobol
once scrambled, and the quasi-Monte Carlo convergence rate; and
yarf.integrate's rqmc taking it by default."""

from __future__ import annotations

import grpc
import numpy as np
import pytest
from scipy.stats import qmc

from yarf import Client, integrate, properties
from yarf.client import array_to_numpy
from yarf.v1 import math_pb2, math_pb2_grpc

DIMENSIONS = 6
SLOPES = np.array([0.5, 0.4, 0.3, 0.6, 0.2, 0.45])
SEEDS = range(20)


def exponential(x: np.ndarray) -> np.ndarray:
    """exp(a · x): smooth, with every variable interacting with all others."""
    return np.exp(x.astype(np.float64) @ SLOPES)


EXACT = float(np.prod(np.expm1(SLOPES) / SLOPES))


def yarf_rmse(client: Client, n: int) -> float:
    """RMS error over SEEDS of the mean of f over n scrambled sobol_nd points."""
    errors = [
        integrate(
            exponential,
            [0.0] * DIMENSIONS,
            [1.0] * DIMENSIONS,
            method="mean_sample",
            sampler="sobol_nd",
            evaluations=n,
            seed=seed,
            server=client,
        ).estimate[0]
        - EXACT
        for seed in SEEDS
    ]
    return float(np.sqrt(np.mean(np.square(errors))))


def scipy_rmse(n: int) -> float:
    """The same for scipy's scrambled Sobol points (LMS and digital shift)."""
    errors = [
        exponential(qmc.Sobol(DIMENSIONS, scramble=True, seed=seed).random(n)).mean() - EXACT
        for seed in SEEDS
    ]
    return float(np.sqrt(np.mean(np.square(errors))))


@pytest.mark.parametrize(("dimensions", "m"), [(1024, 10), (21201, 6)])
def test_unscrambled_points_are_scipys_sobol_sequence_in_every_dimension(
    client: Client, dimensions: int, m: int
) -> None:
    # scipy orders points by Gray code, yarf by index: the first 2^m points
    # are the same set. 24 bits, as many as a float holds.
    handle = client.create("sobol_nd", properties(scramble=False)).handle
    try:
        request = math_pb2.GenerateSamplesRequest(
            handle=handle, first_index=0, count=1 << m, dimensions=dimensions, seed=0
        )
        points = array_to_numpy(math_pb2_grpc.SamplerStub(client.channel).Generate(request).points)
    finally:
        client.release(handle)
    reference = qmc.Sobol(dimensions, scramble=False).random_base2(m)
    ours = {tuple(row) for row in (points.astype(np.float64) * 2**24).astype(np.int64)}
    theirs = {tuple(row) for row in (reference * 2**24).astype(np.int64)}
    assert ours == theirs


def test_scrambled_error_is_within_twice_scipys_at_4096_points(client: Client) -> None:
    ours, theirs = yarf_rmse(client, 4096), scipy_rmse(4096)
    assert ours < 2 * theirs, f"sobol_nd {ours:.3g}, scipy {theirs:.3g}"


def test_error_falls_faster_than_monte_carlo_from_256_to_16384_points(client: Client) -> None:
    # Monte Carlo's error falls as 1/√N: 8 times over this range. A
    # scrambled net on a smooth integrand approaches N^(-3/2), 512 times;
    # ask for at least N^(-3/4) (23 times).
    coarse, fine = yarf_rmse(client, 256), yarf_rmse(client, 16384)
    assert coarse / fine > 64**0.75, f"256 points {coarse:.3g}, 16384 points {fine:.3g}"


def test_rqmc_takes_scrambled_sobol_points_by_default(client: Client) -> None:
    def run(sampler: str | None) -> float:
        kwargs = {} if sampler is None else {"sampler": sampler}
        return integrate(
            exponential,
            [0.0] * DIMENSIONS,
            [1.0] * DIMENSIONS,
            method="rqmc",
            evaluations=1 << 14,
            seed=5,
            server=client,
            **kwargs,
        ).estimate[0]

    default = run(None)
    assert default == run("sobol_nd")
    assert default != run("independent")
    assert abs(default - EXACT) < 1e-4 * EXACT


def test_more_dimensions_than_tabulated_are_refused_by_name(client: Client) -> None:
    with pytest.raises(grpc.RpcError, match="sobol_nd has 21201 dimensions"):
        integrate(
            lambda x: x[:, 0],
            [0.0] * 21202,
            [1.0] * 21202,
            method="rqmc",
            evaluations=64,
            server=client,
        )
