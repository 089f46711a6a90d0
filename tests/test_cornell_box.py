"""The shipped Cornell box: determinism, convergence, encoded results, the CLI."""

from __future__ import annotations

import itertools
import struct
import subprocess
import sys
from pathlib import Path
from statistics import NormalDist

import numpy as np
import pytest
from conftest import CORNELL_BOX
from imagestats import block_z_test

from yarf import Client, LocalServer, RenderResult, component
from yarf.v1 import render_pb2, scene_pb2

SIZE = 256
EXR_MAGIC = b"\x76\x2f\x31\x01"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
CONVERGENCE_SPP = (4, 16, 64)
# The convergence test's film: 128² pixels keep the RMS of a difference
# between seeds within about 1% of its expectation.
CONVERGENCE_SIZE = 128
SEEDS = (1, 2)
# Family-wise false-alarm rate of the statistical checks below.
FAMILY_ALPHA = 1e-4


def sidak_z(tests: int, family_alpha: float = FAMILY_ALPHA) -> float:
    """Two-sided z threshold keeping the family-wise error at family_alpha."""
    alpha = 1.0 - (1.0 - family_alpha) ** (1.0 / tests)
    return NormalDist().inv_cdf(1.0 - alpha / 2.0)


def image_mean(result: RenderResult) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel image mean and the variance of that mean."""
    count = result.pixels.shape[0] * result.pixels.shape[1]
    mean = result.pixels.astype(np.float64).mean(axis=(0, 1))
    variance = result.variance.astype(np.float64).sum(axis=(0, 1)) / count**2
    return mean, variance


def test_cornell_box_scene_file_is_the_256_square_film(cornell_box: scene_pb2.Scene) -> None:
    assert (cornell_box.film.width, cornell_box.film.height) == (SIZE, SIZE)
    assert all(shape.mesh.data for shape in cornell_box.shapes if shape.HasField("mesh"))


def test_same_seed_renders_bitwise_identical_pixels(
    client: Client, cornell_box: scene_pb2.Scene
) -> None:
    first = client.render(cornell_box, spp=4, seed=42)
    second = client.render(cornell_box, spp=4, seed=42)
    assert first.pixels.shape == (SIZE, SIZE, 3)
    assert first.pixels.tobytes() == second.pixels.tobytes()


def test_different_seeds_render_different_pixels(
    client: Client, cornell_box: scene_pb2.Scene
) -> None:
    first = client.render(cornell_box, spp=4, seed=1)
    second = client.render(cornell_box, spp=4, seed=2)
    differing = np.mean(first.pixels != second.pixels)
    assert differing > 0.5, f"only {differing:.1%} of the values differ between seeds 1 and 2"


def test_image_mean_converges_as_samples_per_pixel_grow(
    client: Client, cornell_box: scene_pb2.Scene
) -> None:
    scene = scene_pb2.Scene()
    scene.CopyFrom(cornell_box)
    scene.film.width = scene.film.height = CONVERGENCE_SIZE
    results = {
        (spp, seed): client.render(scene, spp=spp, seed=seed)
        for spp in CONVERGENCE_SPP
        for seed in SEEDS
    }
    for result in results.values():
        assert np.isfinite(result.pixels).all() and np.isfinite(result.variance).all()

    # Per-pixel differences between the two seeds shrink (≈ 1/√spp: ×2 per 4× spp).
    pixel_difference = {
        spp: float(np.sqrt(np.mean((results[spp, 1].pixels - results[spp, 2].pixels) ** 2)))
        for spp in CONVERGENCE_SPP
    }
    for lower, higher in itertools.pairwise(CONVERGENCE_SPP):
        assert pixel_difference[higher] < pixel_difference[lower] / 1.5, (
            f"RMS difference between seeds: {pixel_difference[lower]:.4g} at {lower} spp, "
            f"{pixel_difference[higher]:.4g} at {higher} spp"
        )

    means = {key: image_mean(result) for key, result in results.items()}
    # The standard deviation of the image mean the server reports shrinks too.
    sigma = {spp: np.sqrt(means[spp, 1][1]) for spp in CONVERGENCE_SPP}
    for lower, higher in itertools.pairwise(CONVERGENCE_SPP):
        assert (sigma[higher] < sigma[lower] / 1.5).all(), (
            f"σ of the image mean: {sigma[lower]} at {lower} spp, {sigma[higher]} at {higher}"
        )

    # The seeds' image means differ by no more than their variance allows,
    # and every mean is consistent with the 64-spp mean of both seeds.
    reference = (means[64, 1][0] + means[64, 2][0]) / 2
    reference_variance = (means[64, 1][1] + means[64, 2][1]) / 4
    z_bound = sidak_z(tests=3 * (len(CONVERGENCE_SPP) + 2 * len(CONVERGENCE_SPP)))
    for spp in CONVERGENCE_SPP:
        (mean_1, var_1), (mean_2, var_2) = means[spp, 1], means[spp, 2]
        z = np.abs(mean_1 - mean_2) / np.sqrt(var_1 + var_2)
        assert (z < z_bound).all(), (
            f"{spp} spp: image means of seeds 1 and 2 {mean_1} vs {mean_2} differ by z = {z} "
            f"(bound {z_bound:.2f})"
        )
        for seed in SEEDS:
            mean, variance = means[spp, seed]
            # At 64 spp the mean is part of the reference: compare with the other seed.
            if spp == 64:
                other = means[64, 3 - seed]
                z = np.abs(mean - other[0]) / np.sqrt(variance + other[1])
            else:
                z = np.abs(mean - reference) / np.sqrt(variance + reference_variance)
            assert (z < z_bound).all(), (
                f"{spp} spp seed {seed}: image mean {mean} vs 64-spp mean {reference}: "
                f"z = {z} (bound {z_bound:.2f})"
            )


@pytest.fixture(scope="module")
def finished_job(client: Client, cornell_box: scene_pb2.Scene) -> str:
    job_id = client.submit(cornell_box, spp=4, seed=5, name="encoded-results")
    status = client.wait(job_id, timeout=60)
    assert status.state == render_pb2.SUCCEEDED, status.error
    return job_id


def exr_data_window(data: bytes) -> tuple[int, int, int, int]:
    """The dataWindow (xmin, ymin, xmax, ymax) of a single-part OpenEXR header."""
    position = 8  # magic and version
    while data[position] != 0:
        name_end = data.index(b"\0", position)
        type_end = data.index(b"\0", name_end + 1)
        name = data[position:name_end].decode()
        (size,) = struct.unpack_from("<i", data, type_end + 1)
        value_start = type_end + 5
        if name == "dataWindow":
            return struct.unpack_from("<4i", data, value_start)
        position = value_start + size
    raise AssertionError("the OpenEXR header has no dataWindow")


def test_exr_result_is_an_openexr_file_of_the_film_size(client: Client, finished_job: str) -> None:
    data = client.encoded(finished_job, render_pb2.GetResultRequest.EXR)
    assert data[:4] == EXR_MAGIC, f"EXR bytes start with {data[:8]!r}"
    assert exr_data_window(data) == (0, 0, SIZE - 1, SIZE - 1)


def test_png_result_is_a_png_file_of_the_film_size(client: Client, finished_job: str) -> None:
    data = client.encoded(finished_job, render_pb2.GetResultRequest.PNG)
    assert data[:8] == PNG_SIGNATURE, f"PNG bytes start with {data[:8]!r}"
    assert data[12:16] == b"IHDR"
    assert struct.unpack(">II", data[16:24]) == (SIZE, SIZE)


def yarf_script() -> Path:
    """The `yarf` console script of the Python environment running the tests."""
    script = Path(sys.executable).parent / "yarf"
    assert script.exists(), f"{script} is missing: pip install -e clients/python"
    return script


def test_cli_render_writes_an_exr_file(server: LocalServer, tmp_path: Path) -> None:
    output = tmp_path / "images" / "cornell-box.exr"
    command = [str(yarf_script()), "render", str(CORNELL_BOX), "-o", str(output)]
    command += ["--spp", "4", "--seed", "3", "--server", server.address]
    run = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, f"yarf render failed ({run.returncode}):\n{run.stderr}"
    assert output.read_bytes()[:4] == EXR_MAGIC
    assert str(output) in run.stdout


def test_zsobol_renders_the_image_padded_sobol_renders(
    client: Client, cornell_box: scene_pb2.Scene
) -> None:
    """pbrt-v4's ZSobol (one sequence over the film in Morton order) is a
    choice of points, not of image: both samplers estimate the same pixels."""
    scene = scene_pb2.Scene()
    scene.CopyFrom(cornell_box)
    scene.film.width = scene.film.height = 64
    zsobol = client.render(scene, spp=32, seed=3, sampler=component("zsobol"))
    padded = client.render(scene, spp=32, seed=4, sampler=component("sobol"))
    test = block_z_test(
        zsobol.pixels, zsobol.variance, padded.pixels, padded.variance, block=4, family_alpha=1e-3
    )
    assert not test.failing.size, f"zsobol vs sobol:\n{test.report()}"
