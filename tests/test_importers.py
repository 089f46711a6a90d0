"""Scenes of Mitsuba 3 and pbrt-v4 render in yarf through the importers.

The Mitsuba Cornell box (../shared/scenes/mitsuba-cbox/cbox-rgb.xml), read
by yarf-import, renders as Mitsuba 3 renders the same file: reference mean
and variance images come from independent Mitsuba renders (scalar_rgb),
and every pixel, and every 8×8 block, must pass a z-test with a
Šidák-corrected threshold. The pbrt Cornell box renders the right way
round. A Mitsuba constant emitter lights a diffuse ball as the white
furnace does, and an envmap becomes the constant of Mitsuba's own mean
radiance. The CLI renders and converts both formats, shows the importers'
warnings and reports malformed files in one line with file and line.
"""

from __future__ import annotations

import gzip
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import MITSUBA_CBOX, MITSUBA_CBOX_SIZE, REPO, SHARED
from imagestats import block_z_test

from yarf import Client, LocalServer, RenderResult
from yarf.assets import upload_scene_assets
from yarf.cli import main
from yarf.scene import ImportedScene, SceneError, import_scene, inline_mesh_files, load_scene
from yarf.v1 import render_pb2, scene_pb2

PBRT_CBOX = SHARED / "scenes" / "pbrt-cornell-box" / "scene-v4.pbrt"
TEST_SCENES = REPO / "tests" / "scenes" / "import"
SIZE = MITSUBA_CBOX_SIZE
YARF_SPP = 1024
# Family-wise rate of false alarms over all pixels (or blocks) and channels.
FAMILY_ALPHA = 1e-3


@pytest.fixture(scope="module")
def imported_cbox() -> ImportedScene:
    return import_scene(MITSUBA_CBOX, parameters={"res": str(SIZE)})


@pytest.fixture(scope="module")
def yarf_cbox(client: Client, imported_cbox: ImportedScene) -> RenderResult:
    return client.render(imported_cbox.scene, spp=YARF_SPP, seed=11, timeout=120)


def test_mitsuba_cornell_box_imports_without_warnings(imported_cbox: ImportedScene) -> None:
    assert imported_cbox.warnings == []
    assert imported_cbox.sample_count == 256  # the file's $spp default
    assert (imported_cbox.scene.film.width, imported_cbox.scene.film.height) == (SIZE, SIZE)
    assert len(imported_cbox.scene.shapes) == 8


def test_mitsuba_cornell_box_pixels_match_mitsuba_within_noise(
    yarf_cbox: RenderResult, mitsuba_cbox_reference: tuple[np.ndarray, np.ndarray]
) -> None:
    reference, reference_variance = mitsuba_cbox_reference
    pixels = yarf_cbox.pixels.astype(np.float64)
    assert pixels.shape == reference.shape == (SIZE, SIZE, 3)
    for block in (1, 8):
        test = block_z_test(
            pixels,
            yarf_cbox.variance.astype(np.float64),
            reference,
            reference_variance,
            block=block,
            family_alpha=FAMILY_ALPHA,
        )
        assert len(test.failing) == 0, (
            f"{len(test.failing)} of {test.z.size} {block}×{block} blocks differ from Mitsuba's "
            f"beyond |z| < {test.threshold:.2f} (Šidák, family α = {FAMILY_ALPHA}); "
            f"worst:\n{test.report()}"
        )


def test_mitsuba_cornell_box_renders_with_yarf_render(
    server: LocalServer, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    output = tmp_path / "cbox.exr"
    arguments = [str(MITSUBA_CBOX), "-D", "res=32", "-D", "spp=4", "-o", str(output)]
    code = main(["render", *arguments, "--server", server.address, "-q"])
    assert code == 0
    assert output.stat().st_size > 0
    # Without --spp, the file's sample count (here its $spp) is the job's.
    assert "(4 spp" in capsys.readouterr().out


def test_pbrt_cornell_box_renders_with_yarf_render(server: LocalServer, tmp_path: Path) -> None:
    output = tmp_path / "cornell.exr"
    arguments = [str(PBRT_CBOX), "--spp", "1", "-o", str(output)]
    assert main(["render", *arguments, "--server", server.address, "-q"]) == 0
    assert output.stat().st_size > 0


def test_pbrt_cornell_box_is_the_right_way_round(client: Client) -> None:
    imported = import_scene(PBRT_CBOX)
    assert imported.sample_count == 64
    scene = imported.scene
    scene.film.width = scene.film.height = 32
    pixels = client.render(scene, spp=16, seed=5, timeout=60).pixels.astype(np.float64)
    left, right = pixels[8:24, :4].mean(axis=(0, 1)), pixels[8:24, -4:].mean(axis=(0, 1))
    # The red wall (pbrt's x = -1) on the left, the green one on the right.
    assert left[0] > 2 * left[1], f"left wall {left} is not red"
    assert right[1] > 2 * right[0], f"right wall {right} is not green"
    # The light (seen from below) near the top, the floor darker below it.
    assert pixels[:3, 12:20].mean() > pixels[-3:, 12:20].mean()


def test_a_mitsuba_constant_emitter_lights_a_diffuse_ball_to_half_its_radiance(
    client: Client,
) -> None:
    # The white furnace: a convex ball of reflectance 0.5 under the same
    # radiance from everywhere reflects half of it; the background is all.
    imported = import_scene(TEST_SCENES / "mitsuba_furnace.xml")
    assert imported.warnings == []
    (sky,) = imported.scene.lights
    assert sky.kind == scene_pb2.Light.ENVIRONMENT
    assert sky.emitter.class_name == "constant"
    result = client.render(imported.scene, spp=imported.sample_count, seed=3, timeout=60)
    assert result.pixels.shape == (32, 32, 3)
    radiance = np.array([1.0, 2.0, 0.5])
    # The ball is 11.3 pixels in radius around the centre of the 32×32 image.
    ball = (slice(12, 20), slice(12, 20))
    corners = (np.array([0, 0, 1, 1, 30, 30, 31, 31]), np.array([0, 1, 0, 1, 30, 31, 30, 31]))
    for region, value in ((ball, 0.5 * radiance), (corners, radiance)):
        pixels, sigma = result.pixels[region], np.sqrt(result.variance[region])
        np.testing.assert_allclose(pixels.reshape(-1, 3).mean(axis=0), value, rtol=0.01)
        assert (np.abs(pixels - value) <= 6 * sigma + 0.01 * value).all()


def test_an_envmap_becomes_an_envmap_emitter_turned_by_its_to_world() -> None:
    """Its file, scale and Mitsuba's latitude-longitude mapping carried over,
    and its to_world (90° about +y) as the light's; test_lights.py checks
    the rendered map against Mitsuba's."""
    (sky,) = import_scene(TEST_SCENES / "mitsuba_envmap.xml").scene.lights
    assert sky.kind == scene_pb2.Light.ENVIRONMENT
    assert sky.emitter.class_name == "envmap"
    values = sky.emitter.properties.values
    assert values["filename"].string_value == "assets/sky.pfm"
    assert values["scale"].float_value == 2
    assert values["mapping"].string_value == "latlong"
    turn = np.array(sky.to_world.m).reshape(4, 4)
    np.testing.assert_allclose(turn[:3, :3], [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], atol=1e-12)


@pytest.mark.parametrize(
    "scene",
    sorted(TEST_SCENES.glob("mitsuba_*.xml")) + sorted(TEST_SCENES.glob("pbrt_*.pbrt")),
    ids=lambda path: path.name,
)
def test_every_imported_test_scene_is_accepted_by_the_server(client: Client, scene: Path) -> None:
    """The classes and parameters the importers write are those yarf's components read."""
    imported = import_scene(scene)
    imported.scene.film.width = imported.scene.film.height = 8
    upload_scene_assets(client, imported.scene, scene.parent)
    job_id = client.submit(imported.scene, spp=1, name=scene.name)
    status = client.wait(job_id, timeout=60)
    assert status.state == render_pb2.SUCCEEDED, status.error


def test_convert_writes_a_scene_that_loads(tmp_path: Path) -> None:
    # Beside the input, mesh files stay files; elsewhere they are inlined.
    for output in (tmp_path / "cbox.json", tmp_path / "cbox.textproto"):
        assert main(["convert", str(MITSUBA_CBOX), str(output)]) == 0
        scene = load_scene(output, inline_files=False)
        assert len(scene.shapes) == 8
        assert all(shape.mesh.WhichOneof("source") == "data" for shape in scene.shapes)
    folder = tmp_path / "copy"
    (folder / "assets").mkdir(parents=True)
    (folder / "assets" / "triangle.obj").write_bytes(
        (TEST_SCENES / "assets/triangle.obj").read_bytes()
    )
    (folder / "scene.xml").write_text((TEST_SCENES / "mitsuba_transforms.xml").read_text())
    assert main(["convert", str(folder / "scene.xml"), str(folder / "scene.json")]) == 0
    beside = load_scene(folder / "scene.json", inline_files=False)
    assert beside.shapes[0].mesh.file == "assets/triangle.obj"
    assert load_scene(folder / "scene.json").shapes[0].mesh.data


def test_convert_shows_the_importers_warnings(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert (
        main(["convert", str(TEST_SCENES / "mitsuba_emitters.xml"), str(tmp_path / "e.json")]) == 0
    )
    errors = capsys.readouterr().err
    assert "yarf: warning: " in errors
    assert (
        "mitsuba_emitters.xml:34: sun and sky models are not supported: emitter 'sunsky'" in errors
    )


@pytest.mark.parametrize(
    ("command", "scene", "where"),
    [
        ("convert", "malformed/wrong_type.xml", "wrong_type.xml:3: "),
        ("convert", "malformed/cycle_a.xml", "cycle_b.xml:2: include cycle"),
        ("render", "malformed/unterminated.pbrt", "unterminated.pbrt:3: unterminated string"),
        ("render", "malformed/missing_path.xml", "missing_path.xml:2: <path>: folder 'nowhere'"),
    ],
)
def test_a_malformed_scene_fails_in_one_line_with_file_and_line(
    tmp_path: Path, command: str, scene: str, where: str
) -> None:
    source = str(TEST_SCENES / scene)
    if command == "convert":
        output = tmp_path / "out.json"
        arguments = ["convert", source, str(output)]
    else:
        # The scene fails before any server is asked for.
        output = tmp_path / "out.exr"
        arguments = ["render", source, "-o", str(output), "--server", "127.0.0.1:1"]
    done = subprocess.run(
        [sys.executable, "-m", "yarf.cli", *arguments], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith("yarf: error: ") and where in lines[0], lines[0]
    assert not output.exists()


def test_strict_refuses_what_would_be_ignored_and_names_misspellings(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scene = TEST_SCENES / "mitsuba_materials.xml"
    assert main(["convert", str(scene), str(tmp_path / "loose.json")]) == 0
    assert (
        "parameter 'reflectanse' ignored (did you mean 'reflectance'?)" in capsys.readouterr().err
    )
    assert main(["convert", "--strict", str(scene), str(tmp_path / "strict.json")]) != 0
    assert "--strict refuses what would be ignored or approximated" in capsys.readouterr().err
    assert not (tmp_path / "strict.json").exists()


def test_a_pbrt_image_area_light_shows_its_image_the_right_way_up(
    client: Client, tmp_path: Path
) -> None:
    """pbrt-v4 looks an area light's image up at (u, 1 − v): on a quad whose v
    runs up the screen, the image's top row (red) is at the top."""
    rows = np.array([[[0, 0, 2]] * 2, [[3, 0, 0]] * 2], np.float32)  # PFM: bottom row first
    (tmp_path / "glow.pfm").write_bytes(b"PF\n2 2\n-1.0\n" + rows.tobytes())
    (tmp_path / "glow.pbrt").write_text(
        'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective" "float fov" 20\n'
        'Film "rgb" "integer xresolution" 16 "integer yresolution" 16\n'
        'Sampler "independent" "integer pixelsamples" 4\nWorldBegin\n'
        'AreaLightSource "diffuse" "string filename" "glow.pfm" "float scale" 0.5 '
        '"bool twosided" true\n'
        'Shape "trianglemesh" "point3 P" [-1 -1 0 1 -1 0 1 1 0 -1 1 0] '
        '"point2 uv" [0 0 1 0 1 1 0 1] "integer indices" [0 1 2 0 2 3]\n'
    )
    imported = import_scene(tmp_path / "glow.pbrt")
    assert imported.warnings == []
    upload_scene_assets(client, imported.scene, tmp_path)
    pixels = client.render(imported.scene, spp=4, seed=1, timeout=60).pixels
    np.testing.assert_allclose(pixels[:2].reshape(-1, 3), [[1.5, 0, 0]] * 32, rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(pixels[-2:].reshape(-1, 3), [[0, 0, 1]] * 32, rtol=1e-4, atol=1e-5)


def test_a_conversion_that_takes_too_long_is_stopped_and_named(tmp_path: Path) -> None:
    """A 250 KB pbrt file including 200 cylinders 10 000 times asks for two
    million shapes (the importer stops at 2^24 triangles, after 1.5 s and
    1.2 GB); with a time limit, as the dashboard sets for uploads, it is
    stopped at the limit and the error says so."""
    cylinders = tmp_path / "cylinders.pbrt"
    cylinders.write_text('Shape "cylinder" "float radius" 0.1 "float zmax" 1\n' * 200)
    scene = tmp_path / "many.pbrt"
    scene.write_text(
        'Camera "perspective"\nFilm "rgb" "integer xresolution" 8 "integer yresolution" 8\n'
        "WorldBegin\n" + 'Include "cylinders.pbrt"\n' * 10_000
    )
    with pytest.raises(SceneError, match=r"many\.pbrt: reading the scene took more than 0\.3 s"):
        import_scene(scene, confine=True, timeout=0.3)


def test_gzip_compressed_pbrt_files_and_ply_meshes_render_as_their_plain_copies(
    client: Client, tmp_path: Path
) -> None:
    """pbrt-v4 reads `Include "x.pbrt.gz"`, scene.pbrt.gz itself and `plymesh`
    files named .ply.gz; the importer inflates scene text and yarfd inflates
    meshes. The same scene, compressed and not, renders the same image."""
    ply = (
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "-1 -1 0\n1 -1 0\n1 1 0\n-1 1 0\n4 0 1 2 3\n"
    )
    lamp = 'AreaLightSource "diffuse" "rgb L" [2 1 0.5]\nShape "plymesh" "string filename" "{}"\n'
    head = (
        'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective" "float fov" 30\n'
        'Film "rgb" "integer xresolution" 16 "integer yresolution" 16\nWorldBegin\n'
        'Include "{}"\nShape "sphere" "float radius" 0.3\n'
    )
    for folder, packed in (("plain", False), ("packed", True)):
        (tmp_path / folder).mkdir()
        pack = gzip.compress if packed else (lambda data: data)
        suffix = ".gz" if packed else ""
        (tmp_path / folder / f"quad.ply{suffix}").write_bytes(pack(ply.encode()))
        lamp_text = lamp.format(f"quad.ply{suffix}").encode()
        (tmp_path / folder / f"lamp.pbrt{suffix}").write_bytes(pack(lamp_text))
        scene_text = head.format(f"lamp.pbrt{suffix}").encode()
        (tmp_path / folder / f"scene.pbrt{suffix}").write_bytes(pack(scene_text))
    plain = import_scene(tmp_path / "plain" / "scene.pbrt")
    packed = import_scene(tmp_path / "packed" / "scene.pbrt.gz")
    assert plain.warnings == packed.warnings == []
    (quad,) = [s.mesh for s in packed.scene.shapes if s.HasField("mesh")]
    assert quad.data[:2] == b"\x1f\x8b" and quad.format == "ply"  # sent compressed
    images = [client.render(s.scene, spp=4, seed=3, timeout=60).pixels for s in (plain, packed)]
    assert images[0].mean() > 0.1
    np.testing.assert_array_equal(images[0], images[1])
    # A mesh file named .ply.gz is a PLY file to the client too.
    named = scene_pb2.Scene()
    named.shapes.add(name="quad").mesh.file = "quad.ply.gz"
    inline_mesh_files(named, tmp_path / "packed")
    assert named.shapes[0].mesh.format == "ply" and named.shapes[0].mesh.data[:2] == b"\x1f\x8b"
    # The command line takes scene.pbrt.gz as a pbrt scene too.
    assert (
        main(["convert", str(tmp_path / "packed" / "scene.pbrt.gz"), str(tmp_path / "out.json")])
        == 0
    )


def test_a_pbrt_sphere_cut_to_almost_nothing_renders_as_the_whole_sphere(
    client: Client, tmp_path: Path
) -> None:
    """A partial sphere is meshed with pbrt's uv and normals: one cut by a
    hair's breadth (zmin, zmax, phimax just inside the whole) shades, casts
    shadows and, as an area light, shines as the analytic sphere does."""

    def render(sphere: str) -> RenderResult:
        (tmp_path / "sphere.pbrt").write_text(
            'LookAt 0 3 5  0 0 0  0 1 0\nCamera "perspective" "float fov" 40\n'
            'Film "rgb" "integer xresolution" 32 "integer yresolution" 32\n'
            'Sampler "independent" "integer pixelsamples" 4\nWorldBegin\n'
            'AttributeBegin\nAreaLightSource "diffuse" "rgb L" [4 3 2]\n'
            'Translate 1.5 1.5 0\nShape "sphere" "float radius" 0.4 '
            f"{sphere}\nAttributeEnd\n"
            'Material "diffuse" "rgb reflectance" [0.6 0.6 0.6]\n'
            f'Rotate 90 1 0 0\nShape "sphere" {sphere}\n'
            'Shape "trianglemesh" "point3 P" [-4 -4 1  4 -4 1  4 4 1  -4 4 1] '
            '"integer indices" [0 1 2 0 2 3]\n'
        )
        imported = import_scene(tmp_path / "sphere.pbrt")
        return client.render(imported.scene, spp=256, seed=5, timeout=120)

    whole = render("")
    cut = render('"float zmin" -0.99999 "float zmax" 0.99999 "float phimax" 359.999')
    test = block_z_test(
        cut.pixels, cut.variance, whole.pixels, whole.variance, block=4, family_alpha=1e-3
    )
    assert not test.failing.size, test.report()
    assert np.mean(whole.pixels) > 0.05


@pytest.mark.parametrize(
    "light",
    [
        'Shape "trianglemesh" "point3 P" [-0.5 -0.5 -0.5  0.5 -0.5 -0.5  0.5 0.5 -0.5  '
        '-0.5 0.5 -0.5] "normal N" [0 0 1  0 0 1  0 0 1  0 0 1] "integer indices" [0 1 2 0 2 3]',
        'Shape "cylinder" "float radius" 0.4',
        'Shape "disk" "float radius" 0.5 "float innerradius" 0.2',
        'Shape "sphere" "float radius" 0.4 "float phimax" 300',
    ],
)
def test_pbrt_lights_shine_from_their_side_whichever_way_the_camera_turns(
    client: Client, tmp_path: Path, light: str
) -> None:
    """pbrt's LookAt without `Scale -1 1 1` has the other handedness than
    yarf's camera, which the importer meets by mirroring the world: a mesh
    with normals, and the quadrics meshed with theirs, keep the side they
    shine from, so the two cameras' images are each other's mirror."""

    def render(handedness: str) -> RenderResult:
        (tmp_path / "lit.pbrt").write_text(
            f'{handedness}LookAt 0 3 5  0 0 0  0 1 0\nCamera "perspective" "float fov" 40\n'
            'Film "rgb" "integer xresolution" 32 "integer yresolution" 32\nWorldBegin\n'
            'AttributeBegin\nAreaLightSource "diffuse" "rgb L" [4 3 2]\n'
            f"Translate 1.5 1.5 0\n{light}\nAttributeEnd\n"
            'Rotate 90 1 0 0\nShape "trianglemesh" "point3 P" [-4 -4 1  4 -4 1  4 4 1  -4 4 1] '
            '"integer indices" [0 1 2 0 2 3]\n'
        )
        result = client.render(
            import_scene(tmp_path / "lit.pbrt").scene, spp=64, seed=3, timeout=120
        )
        return result

    mirrored, turned = render(""), render("Scale -1 1 1\n")
    assert np.mean(turned.pixels) > 0.05
    test = block_z_test(
        mirrored.pixels[:, ::-1],
        mirrored.variance[:, ::-1],
        turned.pixels,
        turned.variance,
        block=4,
        family_alpha=1e-3,
    )
    assert not test.failing.size, test.report()
