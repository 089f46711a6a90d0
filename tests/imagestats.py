"""Comparing renders within Monte Carlo noise: block means and z-tests.

A render and a reference each come with the variance of every pixel's
estimate. Means of square blocks of pixels are compared by a z-test whose
threshold is Šidák-corrected for the number of blocks and channels, so
that the whole image raises a false alarm with probability family_alpha.
"""

from __future__ import annotations

from dataclasses import dataclass
from statistics import NormalDist

import numpy as np


def block_means(image: np.ndarray, block: int) -> np.ndarray:
    """Means of block × block tiles (height and width must be multiples of block)."""
    height, width, channels = image.shape
    blocks = image.reshape(height // block, block, width // block, block, channels)
    return blocks.mean(axis=(1, 3))


def mean_and_variance(renders: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The mean of independent renders and the variance of that mean, per pixel."""
    stack = np.stack([np.asarray(r, dtype=np.float64) for r in renders])
    return stack.mean(axis=0), stack.var(axis=0, ddof=1) / len(renders)


@dataclass(frozen=True)
class ZTest:
    """Block z-scores (rows, columns, channels), their threshold and the failures."""

    z: np.ndarray
    threshold: float
    means: np.ndarray
    reference_means: np.ndarray

    @property
    def failing(self) -> np.ndarray:
        return np.argwhere(np.abs(self.z) >= self.threshold)

    def report(self, worst: int = 10) -> str:
        failing = sorted(self.failing.tolist(), key=lambda index: -abs(self.z[tuple(index)]))
        return "\n".join(
            f"  block (row {row}, column {column}) channel {channel}: "
            f"{self.means[row, column, channel]:.5f} vs reference "
            f"{self.reference_means[row, column, channel]:.5f}, "
            f"z = {self.z[row, column, channel]:+.1f}"
            for row, column, channel in failing[:worst]
        )


def block_z_test(
    pixels: np.ndarray,
    variance: np.ndarray,
    reference: np.ndarray,
    reference_variance: np.ndarray,
    *,
    block: int,
    family_alpha: float,
) -> ZTest:
    """z-scores of block means of ``pixels`` against ``reference`` (block 1: per pixel)."""
    means, reference_means = block_means(pixels, block), block_means(reference, block)
    # A block's mean averages block² independent pixels: its variance is
    # the mean of their variances over block².
    difference = means - reference_means
    block_variance = (block_means(variance, block) + block_means(reference_variance, block)) / (
        block**2
    )
    z = np.zeros_like(difference)
    noisy = block_variance > 0
    z[noisy] = difference[noisy] / np.sqrt(block_variance[noisy])
    # Blocks without noise in either image (nothing visible) must agree exactly.
    z[~noisy & (difference != 0)] = np.inf
    alpha = 1.0 - (1.0 - family_alpha) ** (1.0 / z.size)
    threshold = NormalDist().inv_cdf(1.0 - alpha / 2.0)
    return ZTest(z, threshold, means, reference_means)
