"""Splitting a job into tasks, and the task messages nodes pull.

A task renders samples [first_sample, end_sample) of every pixel of a
window of the film. Sample shares of one window are independent estimates
of the same pixels (the same sample points a whole render takes), so they
merge by sample count; tiles paste side by side.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from yarf.v1 import render_pb2

# The first share's size relative to the others' (see _share_bounds).
PREVIEW_SHARE_WEIGHT = 0.25


@dataclass(frozen=True)
class Window:
    """Pixels [x0, x1) × [y0, y1) of the film, y down."""

    x0: int
    y0: int
    x1: int
    y1: int

    @property
    def pixels(self) -> int:
        return (self.x1 - self.x0) * (self.y1 - self.y0)


@dataclass(frozen=True)
class Task:
    """Samples [first_sample, end_sample) of the pixels in ``window``; ``crop`` False: the
    whole film, rendered without a crop window."""

    index: int
    first_sample: int
    end_sample: int
    window: Window
    crop: bool

    @property
    def samples(self) -> int:
        return self.end_sample - self.first_sample

    @property
    def work(self) -> int:
        """Pixel samples: the unit of progress."""
        return self.samples * self.window.pixels


@dataclass(frozen=True)
class SplitPolicy:
    """How finely jobs are cut.

    ``shares``: sample-pass tasks per job (about twice the nodes keeps every
    node busy until the end); ``min_task_work``: pixel samples below which a
    task is not cut further (a task costs a scene fetch and two round trips);
    ``tile_pixels``: images with more pixels are also cut into ``tile_size``²
    crop tiles, so that no node holds a whole large film per task.
    """

    shares: int = 8
    min_task_work: int = 1 << 15
    tile_pixels: int = 1024 * 1024
    tile_size: int = 256


def _tiles(window: Window, size: int) -> list[Window]:
    return [
        Window(x, y, min(x + size, window.x1), min(y + size, window.y1))
        for y in range(window.y0, window.y1, size)
        for x in range(window.x0, window.x1, size)
    ]


def _share_bounds(first: int, end: int, shares: int) -> list[int]:
    """Sample bounds of ``shares`` shares of [first, end), each at least one sample.

    With three shares or more the first is a quarter of the others, so the
    first preview of the job comes back early.
    """
    weights = [PREVIEW_SHARE_WEIGHT] + [1.0] * (shares - 1) if shares >= 3 else [1.0] * shares
    total, cumulative = sum(weights), 0.0
    bounds = [first]
    for i, weight in enumerate(weights):
        cumulative += weight
        bound = first + round((end - first) * cumulative / total)
        # Room for one sample in this share and in each one after it.
        bounds.append(min(max(bound, bounds[-1] + 1), end - (shares - 1 - i)))
    return bounds


def split(
    request: render_pb2.SubmitRequest, splits: render_pb2.JobSplits, policy: SplitPolicy
) -> list[Task]:
    """The tasks of a job (``request.options.spp`` already defaulted).

    ``splits`` says how the job may be divided, as yarfd reads it from the
    capabilities of its classes (SubmitCheck.splits): into sample shares
    when its integrator renders any range of sample passes, and into tiles
    as well when its transport's samples land only in their own pixels and
    the film's filter is no wider than a pixel.
    """
    options = request.options
    film = Window(0, 0, request.scene.film.width, request.scene.film.height)
    window = film
    if options.HasField("crop"):
        window = Window(options.crop.x0, options.crop.y0, options.crop.x1, options.crop.y1)
    first, end = options.first_sample, options.spp
    if not splits.sample_ranges:
        # Other integrators render the job in one piece.
        return [Task(0, first, end, window, options.HasField("crop"))]
    tiles = [window]
    if window.pixels > policy.tile_pixels and splits.tiles:
        tiles = _tiles(window, policy.tile_size)
    tasks: list[Task] = []
    for tile in tiles:
        samples = end - first
        shares = math.ceil(policy.shares / len(tiles))
        shares = max(1, min(shares, samples, tile.pixels * samples // policy.min_task_work))
        bounds = _share_bounds(first, end, shares)
        cropped = tile != film
        tasks += [
            Task(len(tasks) + i, bounds[i], bounds[i + 1], tile, cropped) for i in range(shares)
        ]
    return tasks


def task_options(options: render_pb2.RenderOptions, task: Task) -> render_pb2.RenderOptions:
    """The job's options narrowed to one task."""
    narrowed = render_pb2.RenderOptions()
    narrowed.CopyFrom(options)
    narrowed.spp = task.end_sample
    narrowed.first_sample = task.first_sample
    narrowed.ClearField("crop")
    if task.crop:
        window = task.window
        narrowed.crop.CopyFrom(
            render_pb2.PixelWindow(x0=window.x0, y0=window.y0, x1=window.x1, y1=window.y1)
        )
    return narrowed
