"""Reconstruction filters and the film's exposure as Mitsuba 3 and pbrt-v4 have them.

Mitsuba's filters (Gaussians of any width, Mitchell–Netravali, Catmull-Rom,
Lanczos, the last three with negative lobes) are checked against Mitsuba's
own render of the same file by its pixel z-test: a sphere's silhouette
against the dark, where negative lobes ring. pbrt-v4's imaging ratio (the
shutter's open time × ISO / 100) and `maxcomponentvalue` are checked
against the same scene rendered without them, on the same seed.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from imagestats import mean_and_variance, pixel_z_test
from surface_scenes import SIZE, SPP, write_scene
from test_surfaces import INDEPENDENT

from yarf import Client, load_scene
from yarf.v1 import scene_pb2

SPHERE = (
    '<shape type="sphere"><float name="radius" value="0.8"/>'
    '<bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.5, 0.2"/></bsdf></shape>'
)
# Each Mitsuba rfilter, and its 1-D weight at distance d from a pixel's
# centre as Mitsuba defines it.
FILTERS: dict[str, tuple[str, Callable[[np.ndarray], np.ndarray]]] = {
    "mitchell": ('<rfilter type="mitchell"/>', lambda d: mitchell(d, 1 / 3, 1 / 3)),
    "mitchell B 0.2 C 0.4": (
        '<rfilter type="mitchell"><float name="B" value="0.2"/>'
        '<float name="C" value="0.4"/></rfilter>',
        lambda d: mitchell(d, 0.2, 0.4),
    ),
    "catmullrom": ('<rfilter type="catmullrom"/>', lambda d: mitchell(d, 0, 0.5)),
    "lanczos, 2 lobes": (
        '<rfilter type="lanczos"><integer name="lobes" value="2"/></rfilter>',
        lambda d: np.where(np.abs(d) < 2, np.sinc(d) * np.sinc(d / 2), 0),
    ),
    "gaussian, stddev 1": (
        '<rfilter type="gaussian"><float name="stddev" value="1"/></rfilter>',
        lambda d: np.maximum(np.exp(-(d**2) / 2) - np.exp(-8), 0) * (np.abs(d) < 4),
    ),
}
# The reference's pixels per film pixel, along each axis.
SUPERSAMPLING = 8


def mitchell(d: np.ndarray, b: float, c: float) -> np.ndarray:
    """Mitchell and Netravali's cubic on |d| < 2."""
    x = np.abs(d)
    inner = ((12 - 9 * b - 6 * c) * x**3 + (-18 + 12 * b + 6 * c) * x**2 + (6 - 2 * b)) / 6
    outer = (
        (-b - 6 * c) * x**3 + (6 * b + 30 * c) * x**2 + (-12 * b - 48 * c) * x + 8 * b + 24 * c
    ) / 6
    return np.where(x < 1, inner, np.where(x < 2, outer, 0))


def filtered_scene(folder: Path, rfilter: str, size: int = SIZE) -> Path:
    """The lit sphere against the dark, ``size`` pixels square, under ``rfilter``."""
    path = write_scene(folder, SPHERE)
    text = path.read_text()
    for old, new in [
        ('<rfilter type="box"/>', rfilter),
        (f'<integer name="width" value="{SIZE}"/>', f'<integer name="width" value="{size}"/>'),
        (f'<integer name="height" value="{SIZE}"/>', f'<integer name="height" value="{size}"/>'),
    ]:
        assert old in text
        text = text.replace(old, new)
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def fine_radiance(tmp_path_factory: pytest.TempPathFactory) -> tuple[np.ndarray, np.ndarray]:
    """Mitsuba's render of the scene at SUPERSAMPLING times the resolution,
    box-filtered: each fine pixel's mean radiance, and its variance."""
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    folder = tmp_path_factory.mktemp("fine")
    scene = mi.load_file(str(filtered_scene(folder, '<rfilter type="box"/>', SIZE * SUPERSAMPLING)))
    renders = [np.array(mi.render(scene, spp=16, seed=seed))[..., :3] for seed in range(16)]
    return mean_and_variance(renders)


def filtered(
    fine: tuple[np.ndarray, np.ndarray], weight: Callable[[np.ndarray], np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """Each film pixel's average of the fine image under the filter, weights
    normalised over the film, as camera samples spread evenly converge to;
    and that average's variance."""
    mean, variance = fine
    centres = np.arange(SIZE) + 0.5
    samples = (np.arange(SIZE * SUPERSAMPLING) + 0.5) / SUPERSAMPLING
    w = weight(centres[:, None] - samples[None, :])  # [pixel, fine pixel], both axes alike
    norm = np.outer(w.sum(axis=1), w.sum(axis=1))
    value = np.stack([w @ mean[..., c] @ w.T for c in range(3)], axis=-1) / norm[..., None]
    spread = np.stack([(w**2) @ variance[..., c] @ (w**2).T for c in range(3)], axis=-1)
    return value, spread / norm[..., None] ** 2


@pytest.mark.parametrize("name", list(FILTERS))
def test_filter_averages_mitsubas_radiance_as_mitsubas_filter_defines(
    client: Client,
    tmp_path: Path,
    fine_radiance: tuple[np.ndarray, np.ndarray],
    name: str,
) -> None:
    """Against Mitsuba's radiance at 8× the resolution filtered in numpy, not
    Mitsuba's own filtered render: Mitsuba looks its filter weights up in a
    table of 31 steps over the radius, each the weight at the step's start,
    which next to a high-contrast edge, where a negative lobe's small
    weights decide a pixel, moves it by more than the noise (a dark pixel
    above the lit sphere under Mitchell's filter: −0.0006 in Mitsuba's
    render, −0.0020 in yarf's and in the filter's exact average)."""
    rfilter, weight = FILTERS[name]
    scene = load_scene(filtered_scene(tmp_path, rfilter))
    assert scene.film.filter.kind != scene_pb2.ReconstructionFilter.BOX
    reference, reference_variance = filtered(fine_radiance, weight)
    result = client.render(scene, spp=SPP, seed=3, sampler=INDEPENDENT, timeout=600)
    test = pixel_z_test(result.pixels, result.variance, reference, reference_variance)
    assert test.ok, (
        f"{name}: {100 * test.passed:.2f}% of pixel channels within |z| < {test.threshold:.2f} "
        f"(Mitsuba's bar: 99.75%); worst:\n{test.worst}"
    )


PBRT_SCENE = """LookAt 0 1.5 4  0 0 0  0 1 0
Camera "perspective" "float fov" 40 {camera}
Film "rgb" "integer xresolution" 24 "integer yresolution" 24 {film}
PixelFilter "{pixel_filter}"
WorldBegin
LightSource "infinite" "rgb L" [0.2 0.2 0.2]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [40 40 40]
  Translate 0 2 0
  Rotate 90 1 0 0
  Shape "disk" "float radius" 0.4
AttributeEnd
Material "diffuse" "rgb reflectance" [0.8 0.5 0.2]
Shape "sphere" "float radius" 0.8
"""


def pbrt_scene(
    folder: Path, name: str, camera: str = "", film: str = "", pixel_filter: str = "mitchell"
) -> scene_pb2.Scene:
    path = folder / f"{name}.pbrt"
    path.write_text(PBRT_SCENE.format(camera=camera, film=film, pixel_filter=pixel_filter))
    return load_scene(path)


def test_pbrt_exposure_is_the_shutters_open_time_times_iso_over_100(
    client: Client, tmp_path: Path
) -> None:
    plain = pbrt_scene(tmp_path, "plain")
    exposed = pbrt_scene(
        tmp_path, "exposed", '"float shutteropen" 0.25 "float shutterclose" 0.75', '"float iso" 400'
    )
    assert plain.film.exposure in (0, 1)
    assert exposed.film.exposure == pytest.approx(2)
    assert exposed.film.filter.kind == scene_pb2.ReconstructionFilter.MITCHELL
    a = client.render(plain, spp=16, seed=4, sampler=INDEPENDENT)
    b = client.render(exposed, spp=16, seed=4, sampler=INDEPENDENT)
    # Same seed, same samples: the image exactly doubled.
    np.testing.assert_allclose(b.pixels, 2 * a.pixels, rtol=1e-5, atol=1e-6)


def test_pbrt_maxcomponentvalue_scales_bright_samples_down_to_it(
    client: Client, tmp_path: Path
) -> None:
    # A box filter: under a negative lobe, a bright neighbour cut down
    # would raise a pixel.
    plain = pbrt_scene(tmp_path, "plain", pixel_filter="box")
    limited = pbrt_scene(
        tmp_path, "limited", film='"float maxcomponentvalue" 0.5', pixel_filter="box"
    )
    assert limited.film.max_component_value == pytest.approx(0.5)
    a = client.render(plain, spp=16, seed=4, sampler=INDEPENDENT)
    b = client.render(limited, spp=16, seed=4, sampler=INDEPENDENT)
    # Every sample is cut to 0.5 at most, and only cut: no pixel grows, the
    # lamp's (40 in every component) fall to 0.5, and pixels of the sky
    # alone (0.2 in every sample) stay as they were.
    assert b.pixels.max() < 0.5 + 1e-4 < a.pixels.max()
    assert (b.pixels <= a.pixels + 1e-6).all()
    sky = a.variance.max(axis=2) < 1e-12
    assert sky.sum() > 20
    np.testing.assert_allclose(b.pixels[sky], a.pixels[sky], rtol=1e-6)


def test_film_settings_out_of_range_are_refused_with_their_name(
    client: Client, tmp_path: Path
) -> None:
    scene = pbrt_scene(tmp_path, "plain")
    for field, value in [
        ("exposure", -1.0),
        ("exposure", float("nan")),
        ("exposure", 1e13),
        ("max_component_value", float("inf")),
        ("max_component_value", -2.0),
    ]:
        bad = scene_pb2.Scene()
        bad.CopyFrom(scene)
        setattr(bad.film, field, value)
        with pytest.raises(Exception, match=rf"film\.{field}"):
            client.render(bad, spp=1)
    bad = scene_pb2.Scene()
    bad.CopyFrom(scene)
    bad.film.filter.b = float("nan")
    with pytest.raises(Exception, match=r"film\.filter\.b"):
        client.render(bad, spp=1)
