"""Merging task images by sample count, and their encoding between node and coordinator.

A task's image holds, for each pixel of its window, the mean m of its n
samples and the variance v of that mean. Shares of the same pixels are
independent, so the job's estimate is mean = Σ n_i m_i / Σ n_i, and the
variance of that mean is Σ n_i² v_i / (Σ n_i)².
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from yarf.farm.tasks import Window


@dataclass(frozen=True)
class TaskImage:
    """A task's pixels and variances, float32 [window height, window width, 3]."""

    window: Window
    samples: int
    pixels: np.ndarray
    variance: np.ndarray

    def encode(self) -> bytes:
        """An .npz (no pickles) of the arrays, the window and the sample count."""
        buffer = io.BytesIO()
        np.savez(
            buffer,
            pixels=np.ascontiguousarray(self.pixels, dtype="<f4"),
            variance=np.ascontiguousarray(self.variance, dtype="<f4"),
            window=np.array(
                [self.window.x0, self.window.y0, self.window.x1, self.window.y1], dtype="<i8"
            ),
            samples=np.array(self.samples, dtype="<i8"),
        )
        return buffer.getvalue()

    @classmethod
    def decode(cls, data: bytes) -> TaskImage:
        with np.load(io.BytesIO(data), allow_pickle=False) as arrays:
            window = Window(*(int(v) for v in arrays["window"]))
            image = cls(window, int(arrays["samples"]), arrays["pixels"], arrays["variance"])
        shape = (window.y1 - window.y0, window.x1 - window.x0, 3)
        if image.pixels.shape != shape or image.variance.shape != shape:
            raise ValueError(f"task image of shape {image.pixels.shape} for a window of {shape}")
        return image


class ImageMerge:
    """The running merge of a job's task images over a width × height film."""

    def __init__(self, width: int, height: int) -> None:
        self.width = width
        self.height = height
        self._weighted_sum = np.zeros((height, width, 3))  # Σ n m
        self._weighted_variance = np.zeros((height, width, 3))  # Σ n² v
        self._samples = np.zeros((height, width, 1))  # Σ n

    def add(self, image: TaskImage) -> None:
        w = image.window
        rows, columns = slice(w.y0, w.y1), slice(w.x0, w.x1)
        n = float(image.samples)
        self._weighted_sum[rows, columns] += n * image.pixels.astype(np.float64)
        self._weighted_variance[rows, columns] += n * n * image.variance.astype(np.float64)
        self._samples[rows, columns] += n

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """Pixels and variances, float32 [height, width, 3]; black where no task has finished."""
        n = np.broadcast_to(self._samples, self._weighted_sum.shape)
        pixels = np.zeros_like(self._weighted_sum)
        variance = np.zeros_like(self._weighted_sum)
        np.divide(self._weighted_sum, n, out=pixels, where=n > 0)
        np.divide(self._weighted_variance, n * n, out=variance, where=n > 0)
        return pixels.astype(np.float32), variance.astype(np.float32)
