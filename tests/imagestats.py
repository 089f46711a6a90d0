"""Comparing renders within Monte Carlo noise: block means and z-tests.

A render and a reference each come with the variance of every pixel's
estimate. Means of square blocks of pixels are compared by a z-test whose
threshold is Šidák-corrected for the number of blocks and channels, so
that the whole image raises a false alarm with probability family_alpha.
"""

from __future__ import annotations

from dataclasses import dataclass
from statistics import NormalDist
from typing import Protocol

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


class Render(Protocol):
    """A render's pixels and the variance of each one's estimate (yarf.RenderResult)."""

    pixels: np.ndarray
    variance: np.ndarray


def assert_renders_agree(
    render: Render, reference: Render, label: str, *, block: int = 4, family_alpha: float = 1e-3
) -> None:
    """Every block of ``render`` agrees with ``reference`` within Monte Carlo noise."""
    test = block_z_test(
        render.pixels,
        render.variance,
        reference.pixels,
        reference.variance,
        block=block,
        family_alpha=family_alpha,
    )
    assert not test.failing.size, f"{label}:\n{test.report()}"


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
    # Blocks without noise in either image (nothing visible) must agree; a
    # float32 variance underflows to 0 below pixel values of about 1e-19,
    # so differences under 1e-12, invisible at any exposure, count as none.
    z[~noisy & (np.abs(difference) > 1e-12)] = np.inf
    alpha = 1.0 - (1.0 - family_alpha) ** (1.0 / z.size)
    threshold = NormalDist().inv_cdf(1.0 - alpha / 2.0)
    return ZTest(z, threshold, means, reference_means)


@dataclass(frozen=True)
class PixelTest:
    """Mitsuba's render-regression criterion: per pixel-channel z-tests."""

    passed: float  # fraction of pixel channels within the threshold
    threshold: float
    worst: str

    # Mitsuba's bar: at least this fraction of pixel channels pass.
    REQUIRED = 0.9975

    @property
    def ok(self) -> bool:
        return self.passed >= self.REQUIRED


def pixel_z_test(
    pixels: np.ndarray,
    variance: np.ndarray,
    reference: np.ndarray,
    reference_variance: np.ndarray,
) -> PixelTest:
    """Mitsuba's criterion: each pixel channel's z-score against the reference,
    Šidák-corrected α = 1 − 0.99^(1/pixels); at least 99.75% must pass."""
    pixel_count = pixels.shape[0] * pixels.shape[1]
    alpha = 1.0 - 0.99 ** (1.0 / pixel_count)
    threshold = NormalDist().inv_cdf(1.0 - alpha / 2.0)
    difference = np.asarray(pixels, np.float64) - reference
    total = np.asarray(variance, np.float64) + reference_variance
    z = np.zeros_like(difference)
    # Differences within float32 rounding of the pixel are none: a pixel
    # that sees a constant (a uniform sky) has a variance of rounding alone.
    rounding = np.abs(difference) <= 1e-6 * np.maximum(1.0, np.abs(reference))
    noisy = (total > 0) & ~rounding
    z[noisy] = difference[noisy] / np.sqrt(total[noisy])
    z[~noisy & ~rounding] = np.inf
    failing = np.argwhere(np.abs(z) >= threshold)
    order = sorted(failing.tolist(), key=lambda index: -abs(z[tuple(index)]))[:8]
    worst = "\n".join(
        f"  pixel (row {r}, column {c}) channel {k}: {pixels[r, c, k]:.5f} vs "
        f"{reference[r, c, k]:.5f}, z = {z[r, c, k]:+.1f}"
        for r, c, k in order
    )
    return PixelTest(1.0 - len(failing) / z.size, threshold, worst)
