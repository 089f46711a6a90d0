"""Mitsuba 3's radiancemeter and irradiancemeter, imported and rendered by yarf.

Each meter renders one pixel. Mitsuba 3 (scalar_rgb) renders the same XML
file in independent renders whose spread gives the variance of its mean;
yarf reports its own. The two values must pass a z-test (|z| below the
normal quantile of α = 1e-3 per channel, Šidák-corrected over the three).
An irradiance meter under a uniform sky reads π·L, and less under an
occluder, by the view factor of a point to a parallel square.
"""

from __future__ import annotations

import math
import shutil
import time
from pathlib import Path
from statistics import NormalDist

import numpy as np
import pytest
from conftest import SHARED
from imagestats import mean_and_variance

from yarf import Client, RenderResult, component, load_scene
from yarf.v1 import render_pb2, scene_pb2

CBOX = SHARED / "scenes" / "mitsuba-cbox"
INDEPENDENT = scene_pb2.ComponentSpec(class_name="independent")
MITSUBA_RENDERS = 16
MITSUBA_SPP = 32768
YARF_SPP = 1 << 19
# Family-wise false-alarm rate over the three channels of a comparison.
FAMILY_ALPHA = 1e-3
THRESHOLD = NormalDist().inv_cdf(1 - (1 - (1 - FAMILY_ALPHA) ** (1 / 3)) / 2)

ONE_PIXEL = """
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="1"/><integer name="height" value="1"/>
            <rfilter type="box"/>
        </film>"""

RADIANCE_METER = f"""
    <sensor type="radiancemeter">
        <point name="origin" value="278, 400, 300"/>
        <vector name="direction" value="-1, 0, 0"/>{ONE_PIXEL}
    </sensor>"""

# A 80 × 80 square lying 1 unit above the floor, facing up, clear of both boxes.
FLOOR_METER = f"""
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="40"/><rotate x="1" angle="-90"/><translate x="420" y="1" z="120"/>
        </transform>
        <sensor type="irradiancemeter">{ONE_PIXEL}
        </sensor>
    </shape>"""


def cbox_scene(folder: Path, sensor: str) -> Path:
    """Mitsuba's Cornell box (path tracer, max_depth 6) seen by `sensor` alone."""
    shutil.copytree(CBOX / "fragments", folder / "fragments")
    shutil.copytree(CBOX / "meshes", folder / "meshes")
    path = folder / "meter.xml"
    path.write_text(f"""<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="6"/></integrator>
    <include filename="fragments/bsdfs-rgb.xml"/>
    <include filename="fragments/shapes.xml"/>
    <emitter type="area" id="area-emitter">
        <rgb name="radiance" value="18.387, 10.9873, 2.75357"/>
    </emitter>
    {sensor}
</scene>
""")
    return path


def render_mitsuba(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Mitsuba's value of the one pixel and the variance of that value."""
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    scene = mi.load_file(str(path))
    start = time.monotonic()
    renders = [
        np.array(mi.render(scene, spp=MITSUBA_SPP, seed=seed), dtype=np.float64)[0, 0, :3]
        for seed in range(MITSUBA_RENDERS)
    ]
    print(f"Mitsuba: {MITSUBA_RENDERS} × {MITSUBA_SPP} spp in {time.monotonic() - start:.1f} s")
    return mean_and_variance(renders)


def render_yarf(client: Client, scene: scene_pb2.Scene, **options: object) -> RenderResult:
    result = client.render(scene, spp=YARF_SPP, seed=5, sampler=INDEPENDENT, timeout=120, **options)
    assert result.pixels.shape == (1, 1, 3)
    return result


def assert_agrees_with_mitsuba(client: Client, path: Path, label: str) -> None:
    reference, reference_variance = render_mitsuba(path)
    result = render_yarf(client, load_scene(path))
    value = result.pixels[0, 0].astype(np.float64)
    variance = result.variance[0, 0].astype(np.float64)
    z = (value - reference) / np.sqrt(variance + reference_variance)
    report = "\n".join(
        f"  {channel}: yarf {value[k]:.5f} ± {math.sqrt(variance[k]):.5f}, "
        f"Mitsuba {reference[k]:.5f} ± {math.sqrt(reference_variance[k]):.5f}, z = {z[k]:+.2f}"
        for k, channel in enumerate("RGB")
    )
    print(f"{label}:\n{report}")
    assert (np.abs(z) < THRESHOLD).all(), f"{label} differs beyond |z| < {THRESHOLD:.2f}:\n{report}"


def test_radiance_meter_in_the_cornell_box_matches_mitsuba(client: Client, tmp_path: Path) -> None:
    path = cbox_scene(tmp_path, RADIANCE_METER)
    scene = load_scene(path)
    assert scene.camera.model == scene_pb2.Camera.RADIANCE_METER
    assert_agrees_with_mitsuba(client, path, "radiance meter on the green wall")


def test_irradiance_meter_on_the_cornell_box_floor_matches_mitsuba(
    client: Client, tmp_path: Path
) -> None:
    path = cbox_scene(tmp_path, FLOOR_METER)
    scene = load_scene(path)
    assert scene.camera.model == scene_pb2.Camera.IRRADIANCE_METER
    assert scene.camera.meter_shape in {shape.name for shape in scene.shapes}
    assert_agrees_with_mitsuba(client, path, "irradiance meter on the floor")


SKY = 0.7, 0.4, 0.2


def sky_scene(folder: Path, shapes: str) -> Path:
    path = folder / "sky.xml"
    path.write_text(f"""<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="8"/></integrator>
    <emitter type="constant"><rgb name="radiance" value="{", ".join(map(str, SKY))}"/></emitter>
    {shapes}
</scene>
""")
    return path


def test_irradiance_meter_under_a_uniform_sky_reads_pi_times_its_radiance(
    client: Client, tmp_path: Path
) -> None:
    meter = f"""<shape type="disk">
        <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="30"/></transform>
        <sensor type="irradiancemeter">{ONE_PIXEL}</sensor>
    </shape>"""
    result = render_yarf(client, load_scene(sky_scene(tmp_path, meter)))
    print(f"uniform sky: {result.pixels[0, 0]} (π·L = {np.pi * np.array(SKY)})")
    # Every ray escapes to the same radiance: exact but for rounding.
    np.testing.assert_allclose(result.pixels[0, 0], np.pi * np.array(SKY), rtol=1e-5)


def square_view_factor(half_side: float, height: float) -> float:
    """The view factor from a point to a parallel square centred above it:
    four times that to a rectangle with a corner above the point."""
    a = half_side / height
    s = math.sqrt(1 + a * a)
    return 4 * (2 * (a / s) * math.atan(a / s)) / (2 * math.pi)


def test_irradiance_meter_under_an_occluder_reads_the_sky_it_sees(
    client: Client, tmp_path: Path
) -> None:
    # A small meter square (half side 0.01) below a black square of half
    # side 1 at height 1: it sees the sky outside the occluder's view factor.
    shapes = f"""<shape type="rectangle">
        <transform name="to_world"><scale value="0.01"/><rotate x="1" angle="-90"/></transform>
        <sensor type="irradiancemeter">{ONE_PIXEL}</sensor>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="90"/><translate y="1"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    </shape>"""
    result = render_yarf(client, load_scene(sky_scene(tmp_path, shapes)))
    value = result.pixels[0, 0].astype(np.float64)
    sigma = np.sqrt(result.variance[0, 0].astype(np.float64))
    factor = square_view_factor(1.0, 1.0)
    expected = np.pi * np.array(SKY) * (1 - factor)
    z = (value - expected) / sigma
    print(
        f"occluded sky: {value} ± {sigma}, analytic {expected} (view factor {factor:.4f}), z = {z}"
    )
    assert (value < 0.9 * np.pi * np.array(SKY)).all()
    assert (np.abs(z) < THRESHOLD).all(), f"{value} ± {sigma} vs {expected}: z = {z}"


@pytest.mark.parametrize("transport", ["light", "bdpt"])
@pytest.mark.parametrize("meter", ["a radiance meter", "an irradiance meter"])
def test_light_paths_refuse_a_meter(
    client: Client, tmp_path: Path, transport: str, meter: str
) -> None:
    sensor = RADIANCE_METER if meter == "a radiance meter" else FLOOR_METER
    scene = load_scene(cbox_scene(tmp_path, sensor))
    job = client.submit(scene, spp=1, transport=component(transport))
    status = client.wait(job, timeout=60)
    assert status.state == render_pb2.FAILED
    assert f"{transport}: {meter} cannot be reached by light paths" in status.error
    assert "render it with path" in status.error
