"""py_halton: the Halton sequence with random digit permutations, as a Python Sampler.

Coordinate d of point i is the radical inverse of i in the d-th prime base
(2, 3, 5, 7, ...), each of its digits passed through a permutation of
{0..b-1} drawn for that digit position from (seed, d). Permuting whole
digit positions keeps Halton's stratification (in base b, b^k consecutive
points from a multiple of b^k fill the b^k intervals [j/b^k, (j+1)/b^k)
once each), while each point becomes uniform over seeds, so averages over
seeds give unbiased error estimates. Past the 256th dimension the bases
repeat, with their own permutations.

Deterministic and stateless: the same (index, dimension, seed) always gives
the same number in [0, 1). No properties.
"""

from __future__ import annotations

import functools

import numpy as np

from yarf_component import Sampler

# Keeps these permutations apart from other uses of the same seeds.
SALT = 0x48414C54  # "HALT"
# Digits that carry a coordinate's precision (beyond float32's 24 bits).
PRECISION_BITS = 32
LARGEST_BELOW_ONE = np.nextafter(np.float32(1), np.float32(0))


def first_primes(count: int) -> np.ndarray:
    limit = 2048
    sieve = np.ones(limit, dtype=bool)
    sieve[:2] = False
    for k in range(2, int(limit**0.5) + 1):
        if sieve[k]:
            sieve[k * k :: k] = False
    return np.flatnonzero(sieve)[:count]


PRIMES = first_primes(256)


@functools.lru_cache(maxsize=4096)
def digit_permutations(base: int, digits: int, seed: int, dimension: int) -> np.ndarray:
    """[digits, base]: one permutation of {0..base-1} per digit position."""
    rng = np.random.default_rng([SALT, seed, dimension])
    return rng.permuted(np.tile(np.arange(base, dtype=np.uint64), (digits, 1)), axis=1)


def scrambled_radical_inverse(
    index: np.ndarray, base: int, seed: int, dimension: int
) -> np.ndarray:
    """[N] float64: the permuted radical inverses of uint64 indices in ``base``."""
    # Every digit position up to the precision, also past the index's own
    # digits: a permutation maps their zeros to anything.
    largest = int(index.max()) if index.size else 0
    digits = max(int(np.ceil(PRECISION_BITS / np.log2(base))), 1)
    while base**digits <= largest:
        digits += 1
    permutations = digit_permutations(base, digits, seed, dimension)
    value = np.zeros(index.shape, np.float64)
    rest = index.copy()
    scale = 1.0
    b = np.uint64(base)
    for position in range(digits):
        scale /= base
        value += permutations[position][rest % b] * scale
        rest //= b
    return value


class Halton(Sampler):
    class_name = "py_halton"
    summary = "Halton sequence with random digit permutations per seed, in Python"

    def generate(self, first_index: int, count: int, dimensions: int, seed: int) -> np.ndarray:
        index = np.arange(count, dtype=np.uint64) + np.uint64(first_index)
        points = np.empty((count, dimensions), np.float32)
        for d in range(dimensions):
            base = int(PRIMES[d % len(PRIMES)])
            points[:, d] = scrambled_radical_inverse(index, base, seed, d)
        # Rounding to float32 must not reach 1.
        return np.minimum(points, LARGEST_BELOW_ONE)
