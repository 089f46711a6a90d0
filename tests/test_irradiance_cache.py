"""The irradiance cache against the path tracer, its accuracy trend, and its cache file.

The irradiance_cache transport computes emission, direct light and one
indirect diffuse bounce (records gather the direct light their hemisphere
sees): the paths of at most three segments, what the path tracer computes
with max_depth 3. On the diffuse Cornell box at 32×32 pixels, a tight
accuracy (a = 0.1) agrees with a low-noise path-traced reference in the
image mean (3% per channel) and in the means of 4×4-pixel blocks away from
the light's edge, relative to each block (RMS under 3%, every block under
12%; measured 1.2% and 5.8%). A loose accuracy (a = 1) makes under a
quarter of the records and over three times the RMS block error
(measured: 1770 and 100 records, RMS 1.2% and 10.5%). A cache file
written by one job is read by the next: the second makes no records (the
file is left as it is), traces far fewer rays, takes less time and renders
the same image; a scene with another light does not reuse it.
"""

from __future__ import annotations

from pathlib import Path

import grpc
import numpy as np
import pytest

from yarf import Client, LocalServer, RenderError, RenderResult, component, rgb
from yarf.scene import PropertyValue
from yarf.v1 import scene_pb2

SIZE = 32
BLOCK = 4
REFERENCE_SPP = 4096
CACHE_SPP = 1024
INDEPENDENT = scene_pb2.ComponentSpec(class_name="independent")
# Cache file header: magic, version, floats per record, scene key, record count.
KEY_OFFSET, COUNT_OFFSET = 16, 24


def small(cornell_box: scene_pb2.Scene) -> scene_pb2.Scene:
    scene = scene_pb2.Scene()
    scene.CopyFrom(cornell_box)
    scene.film.width = scene.film.height = SIZE
    return scene


def irradiance_cache(**properties: PropertyValue) -> scene_pb2.ComponentSpec:
    return component("irradiance_cache", **properties)


def render(
    client: Client, scene: scene_pb2.Scene, transport: scene_pb2.ComponentSpec, spp: int, seed: int
) -> RenderResult:
    result = client.render(
        scene, spp=spp, seed=seed, transport=transport, sampler=INDEPENDENT, timeout=600
    )
    assert np.isfinite(result.pixels).all()
    return result


def record_count(cache_file: Path) -> int:
    return int.from_bytes(cache_file.read_bytes()[COUNT_OFFSET : COUNT_OFFSET + 8], "little")


def block_means(image: np.ndarray) -> np.ndarray:
    rows, columns = image.shape[0] // BLOCK, image.shape[1] // BLOCK
    return image.reshape(rows, BLOCK, columns, BLOCK, -1).mean(axis=(1, 3))


def block_errors(pixels: np.ndarray, reference: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Relative errors of the BLOCK × BLOCK block means where ``keep``, per channel."""
    return ((block_means(pixels) - block_means(reference)) / block_means(reference))[keep]


def rms(errors: np.ndarray) -> float:
    return float(np.sqrt((errors**2).mean()))


@pytest.fixture
def cache_folder(server: LocalServer) -> Path:
    """Where the server keeps the local user's component files: cache_file names lie there."""
    return server.state_path / "files" / "local"


@pytest.fixture(scope="module")
def reference(client: Client, cornell_box: scene_pb2.Scene) -> RenderResult:
    """Emission, direct light and one indirect bounce, path traced."""
    return render(client, small(cornell_box), component("path", max_depth=3), REFERENCE_SPP, 1)


@pytest.fixture(scope="module")
def unlit_blocks(client: Client, cornell_box: scene_pb2.Scene) -> np.ndarray:
    """The blocks where no emitter is in view, within a pixel.

    Pixels the light's edge crosses carry its radiance in a small fraction
    of their samples: the noisiest pixels of both renders, left out of the
    block comparison (the image mean still counts them).
    """
    emission = render(client, small(cornell_box), component("path", max_depth=1), 16, 1)
    lit = np.pad(emission.pixels.max(axis=2) > 0, 1)
    near_lit = np.zeros_like(lit)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near_lit |= np.roll(lit, (dy, dx), axis=(0, 1))
    near_lit = near_lit[1:-1, 1:-1, np.newaxis].astype(np.float32)
    return block_means(near_lit)[..., 0] == 0


def test_tight_accuracy_matches_the_path_tracer_and_loose_accuracy_errs_more(
    client: Client,
    cornell_box: scene_pb2.Scene,
    reference: RenderResult,
    unlit_blocks: np.ndarray,
    cache_folder: Path,
) -> None:
    scene = small(cornell_box)
    errors: dict[float, np.ndarray] = {}
    records: dict[float, int] = {}
    for accuracy in (0.1, 1.0):
        name = f"accuracy-{accuracy}.irc"
        cache_file = cache_folder / name
        transport = irradiance_cache(accuracy=accuracy, cache_file=name)
        result = render(client, scene, transport, CACHE_SPP, 2)
        records[accuracy] = record_count(cache_file)
        errors[accuracy] = block_errors(result.pixels, reference.pixels, unlit_blocks)
        if accuracy == 0.1:
            mean, reference_mean = (
                result.pixels.mean(axis=(0, 1)),
                reference.pixels.mean(axis=(0, 1)),
            )
            assert np.allclose(mean, reference_mean, rtol=0.03), (mean, reference_mean)
    tight, loose = errors[0.1], errors[1.0]
    report = (
        f"records {records}, block error RMS {rms(tight):.4f} (a 0.1) {rms(loose):.4f} (a 1), "
        f"worst {np.abs(tight).max():.4f} (a 0.1) {np.abs(loose).max():.4f} (a 1)"
    )
    assert rms(tight) < 0.03 and np.abs(tight).max() < 0.12, report
    assert records[1.0] * 4 < records[0.1], report
    assert rms(loose) > 3 * rms(tight), report


def test_a_cache_file_is_reused_by_the_next_job(
    client: Client, cornell_box: scene_pb2.Scene, cache_folder: Path
) -> None:
    scene = small(cornell_box)
    cache_file = cache_folder / "cornell.irc"
    cache_file.unlink(missing_ok=True)
    transport = irradiance_cache(accuracy=0.15, cache_file=cache_file.name)
    first = render(client, scene, transport, 4, 3)
    written = cache_file.read_bytes()
    written_at = cache_file.stat().st_mtime_ns
    assert record_count(cache_file) > 100

    second = render(client, scene, transport, 4, 3)
    # No record made: the file is not written again.
    assert cache_file.stat().st_mtime_ns == written_at and cache_file.read_bytes() == written
    # The records' gather rays are not traced again, and Prepare is quicker.
    assert second.status.closest_hit_rays * 4 < first.status.closest_hit_rays, (
        first.status.closest_hit_rays,
        second.status.closest_hit_rays,
    )
    assert second.status.elapsed_seconds < first.status.elapsed_seconds
    np.testing.assert_array_equal(first.pixels, second.pixels)

    # Another scene (a dimmer light) does not use them: they are made anew.
    dimmer = small(cornell_box)
    light = next(shape for shape in dimmer.shapes if shape.HasField("emitter"))
    light.emitter.CopyFrom(component("diffuse_area", radiance=rgb(1.0)))
    render(client, dimmer, transport, 4, 3)
    rebuilt = cache_file.read_bytes()
    assert rebuilt[KEY_OFFSET : KEY_OFFSET + 8] != written[KEY_OFFSET : KEY_OFFSET + 8]


@pytest.mark.parametrize(
    ("properties", "message"),
    [
        ({"accuracy": 0.0}, "accuracy"),
        ({"accuracy": -1.0}, "accuracy"),
        ({"gather_rays": 4}, "gather_rays"),
        ({"min_spacing": 0.2, "max_spacing": 0.1}, "max_spacing"),
        ({"max_depth": 0}, "max_depth"),
        ({"prepare_grid": 0}, "prepare_grid"),
        ({"cache_file": "/nonexistent-directory/records.irc"}, "plain file name"),
        ({"cache_file": "../tokens"}, "plain file name"),
        ({"cache_file": ".hidden"}, "plain file name"),
        ({"acuracy": 0.1}, "has no parameter 'acuracy'; did you mean 'accuracy'?"),
    ],
)
def test_a_bad_property_is_refused_with_a_clear_error(
    client: Client, cornell_box: scene_pb2.Scene, properties: dict[str, PropertyValue], message: str
) -> None:
    """At Submit where the declared parameters refuse it, else when the job runs."""
    scene = small(cornell_box)
    scene.film.width = scene.film.height = 8
    with pytest.raises((grpc.RpcError, RenderError)) as failure:
        render(client, scene, irradiance_cache(**properties), 1, 0)
    assert message in str(failure.value), str(failure.value)
