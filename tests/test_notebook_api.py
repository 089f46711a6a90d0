"""The notebook API: ``yarf.render``, ``yarf.load`` and a scene's ``params``.

Renders of the Cornell box at a few pixels and samples: the image has the
film's size and finite non-negative pixels; the process's embedded yarfd
is shared by its renders and gone when the process exits; the parameter
view lists and checks what it edits, and an edit changes the next render
(a black wall darkens it beyond its noise; twice the light's radiance
doubles every pixel, the random numbers being the same for the same
seed). docs/notebook.ipynb runs from top to bottom in a kernel of this
venv and shows an image.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import yarf
from yarf import Client

REPO = Path(__file__).resolve().parents[1]
CORNELL_BOX = REPO / "scenes" / "cornell-box" / "scene.json"
PBRT_CBOX = REPO.parent / "shared" / "scenes" / "pbrt-cornell-box" / "scene-v4.pbrt"
MITSUBA_CBOX = REPO.parent / "shared" / "scenes" / "mitsuba-cbox" / "cbox-rgb.xml"
NOTEBOOK = REPO / "docs" / "notebook.ipynb"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def check_image(image: yarf.Image, width: int, height: int) -> None:
    pixels = np.asarray(image)
    assert pixels.shape == (height, width, 3)
    assert pixels.dtype == np.float32
    assert np.all(np.isfinite(pixels)) and np.all(pixels >= 0.0)
    assert pixels.mean() > 0.0
    assert image.variance is not None and image.variance.shape == pixels.shape
    assert image.aovs == {}
    assert image.seconds > 0.0


def test_render_of_a_path_uses_the_embedded_server() -> None:
    image = yarf.render(CORNELL_BOX, spp=4, res="24x16")
    check_image(image, 24, 16)
    assert image.spp == 4


def test_render_of_a_loaded_scene_has_its_film_size(client: Client) -> None:
    scene = yarf.load(CORNELL_BOX)
    scene.message.film.width, scene.message.film.height = 20, 12
    image = yarf.render(scene, spp=2, server=client)
    check_image(image, 20, 12)
    assert image.spp == 2


def test_render_on_a_given_server_or_address(server: yarf.LocalServer) -> None:
    for given in (server, server.address):
        image = yarf.render(CORNELL_BOX, spp=1, res=(8, 8), server=given)
        check_image(image, 8, 8)


def test_the_embedded_server_is_shared_by_renders() -> None:
    yarf.render(CORNELL_BOX, spp=1, res=(8, 8))
    first = yarf.embedded_server()
    yarf.render(yarf.load(CORNELL_BOX), spp=1, res=(8, 8))
    second = yarf.embedded_server()
    assert second is first and second.address == first.address and second.pid == first.pid
    assert first.is_running()


def test_the_embedded_server_stops_when_the_process_exits() -> None:
    program = textwrap.dedent(
        f"""
        import yarf
        yarf.render({str(CORNELL_BOX)!r}, spp=1, res=(8, 8))
        print(yarf.embedded_server().pid, flush=True)
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", program], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    pid = int(done.stdout.split()[-1])
    # The process waited for its yarfd: no such process is left, not even as an orphan.
    cmdline = Path(f"/proc/{pid}/cmdline")
    assert not cmdline.exists() or b"yarfd" not in cmdline.read_bytes()


def test_a_bad_option_is_refused_before_anything_renders() -> None:
    with pytest.raises(yarf.OptionError, match="spp"):
        yarf.render(CORNELL_BOX, spp=0)
    with pytest.raises(yarf.OptionError, match="res"):
        yarf.render(CORNELL_BOX, res="big")
    with pytest.raises(TypeError, match="scene file"):
        yarf.render(42)  # type: ignore[arg-type]


def test_params_list_materials_emitters_and_camera_with_their_types() -> None:
    params = yarf.load(CORNELL_BOX).params
    types = params.types()
    for wall in ("red", "green", "white", "box", "light"):
        assert types[f"{wall}.reflectance"] == "rgb"
    assert types["luminaire.radiance"] == "rgb"
    assert types["camera.fov"] == "float"
    assert types["camera.origin"] == "vec3"
    assert types["camera.to_world"] == "transform"
    assert list(params.keys()) == list(types)
    assert params["red.reflectance"] == pytest.approx([0.570068, 0.0430135, 0.0443706])
    assert params["camera.fov"] == pytest.approx(39.3077)
    table = repr(params)
    assert "red.reflectance" in table and "rgb" in table and "0.5701" in table


def test_camera_to_world_is_the_look_at_frame() -> None:
    scene = yarf.load(CORNELL_BOX)
    matrix = scene.params["camera.to_world"]
    assert np.allclose(matrix[:3, 3], [278, 273, -800])
    assert np.allclose(matrix[:3, 2], [0, 0, 1])
    moved = matrix.copy()
    moved[:3, 3] += [0, 0, 100]
    scene.params["camera.to_world"] = moved
    assert np.allclose(scene.params["camera.origin"], [278, 273, -700])
    assert np.allclose(scene.params["camera.to_world"], moved)


@pytest.mark.parametrize("path", [PBRT_CBOX, MITSUBA_CBOX], ids=["pbrt", "mitsuba"])
def test_params_of_an_imported_scene(path: Path) -> None:
    # ../shared stands beside the repository wherever the tests run.
    assert path.exists(), f"{path} is missing: the shared scenes must stand beside the repository"
    scene = yarf.load(path)
    assert scene.sample_count > 0
    types = scene.params.types()
    assert any(kind == "rgb" and key.endswith(".reflectance") for key, kind in types.items())
    # Its emitting shape has no name: it is named by its place.
    assert any(key.startswith("shapes[") and key.endswith(".radiance") for key in types)
    assert types["camera.fov"] == "float"


def test_an_unknown_key_names_the_closest() -> None:
    params = yarf.load(CORNELL_BOX).params
    with pytest.raises(KeyError, match=r"did you mean 'red.reflectance'") as raised:
        params["red.reflectanse"] = 0.5
    assert isinstance(raised.value, yarf.UnknownParameterError)
    assert "red.reflectance" in raised.value.suggestions
    with pytest.raises(KeyError, match=r"luminaire\.radiance"):
        params["luminaire.radiense"]
    assert "red.reflectanse" not in params


@pytest.mark.parametrize(
    ("key", "value", "error", "message"),
    [
        ("red.reflectance", "red", TypeError, "sequence of 3 numbers"),
        ("red.reflectance", [0.1, 0.2], ValueError, r"shape \(3,\)"),
        ("red.reflectance", [0.1, float("nan"), 0.2], ValueError, "finite"),
        ("red.reflectance", True, TypeError, "sequence of 3 numbers"),
        ("camera.fov", [40.0], TypeError, "is a float"),
        ("camera.fov", "40", TypeError, "is a float"),
        ("camera.origin", np.zeros((3, 1)), ValueError, r"shape \(3,\)"),
        ("camera.to_world", np.eye(3), ValueError, r"shape \(4, 4\)"),
        ("luminaire.radiance", {"r": 1}, TypeError, "sequence of 3 numbers"),
    ],
)
def test_a_value_of_another_type_or_shape_is_refused(
    key: str, value: object, error: type[Exception], message: str
) -> None:
    scene = yarf.load(CORNELL_BOX)
    before = scene.message.SerializeToString()
    with pytest.raises(error, match=message):
        scene.params[key] = value
    assert scene.message.SerializeToString() == before


def test_parameters_cannot_be_removed() -> None:
    with pytest.raises(TypeError, match="cannot be removed"):
        del yarf.load(CORNELL_BOX).params["red.reflectance"]


def test_a_black_wall_darkens_the_image(client: Client) -> None:
    scene = yarf.load(CORNELL_BOX)
    options = {"spp": 32, "seed": 3, "res": (32, 32), "server": client}
    lit = yarf.render(scene, **options)
    scene.params["red.reflectance"] = 0.0
    red = scene.message.materials[2]
    assert red.name == "red"
    assert red.properties.values["reflectance"].WhichOneof("value") == "rgb_value"
    assert scene.params["red.reflectance"] == pytest.approx([0.0, 0.0, 0.0])
    dark = yarf.render(scene, **options)
    assert lit.variance is not None and dark.variance is not None
    # The standard error of each image's mean, as if the two were independent
    # (the same seed correlates them, which only narrows their difference's spread).
    pixels = lit.pixels[..., 0].size
    red_error = np.sqrt((lit.variance[..., 0].mean() + dark.variance[..., 0].mean()) / pixels)
    darker = np.asarray(lit)[..., 0].mean() - np.asarray(dark)[..., 0].mean()
    assert darker > 5 * red_error, (darker, red_error)
    error = np.sqrt((lit.variance.mean() + dark.variance.mean()) / (3 * pixels))
    assert lit.mean() - dark.mean() > 5 * error, (lit.mean() - dark.mean(), error)


def test_twice_the_radiance_doubles_every_pixel(client: Client) -> None:
    scene = yarf.load(CORNELL_BOX)
    options = {"spp": 4, "seed": 11, "res": (24, 24), "server": client}
    base = np.asarray(yarf.render(scene, **options))
    scene.params["luminaire.radiance"] = 2 * scene.params["luminaire.radiance"]
    doubled = np.asarray(yarf.render(scene, **options))
    # One light: its share of the light samples does not change, nor does any
    # random choice of the path tracer, so each pixel is twice its value.
    np.testing.assert_allclose(doubled, 2 * base, rtol=1e-5, atol=1e-7)


def test_an_image_shows_itself_and_saves(tmp_path: Path) -> None:
    image = yarf.render(CORNELL_BOX, spp=1, res=(16, 8))
    png = image._repr_png_()
    assert png.startswith(PNG_SIGNATURE)
    assert "data:image/png;base64," in image._repr_html_()
    image.save(tmp_path / "box.png")
    assert (tmp_path / "box.png").read_bytes().startswith(PNG_SIGNATURE)
    image.save(tmp_path / "box.exr")
    from yarf.images import decode_exr

    assert np.array_equal(decode_exr((tmp_path / "box.exr").read_bytes()), np.asarray(image))
    with pytest.raises(ValueError, match="extension"):
        image.save(tmp_path / "box.jpg")


def test_the_notebook_runs_and_shows_an_image() -> None:
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    from jupyter_client.kernelspec import KernelSpecManager
    from jupyter_client.manager import KernelManager

    # The kernel of this venv's ipykernel, started with this Python, whatever
    # kernels the user has installed elsewhere.
    specs = KernelSpecManager(kernel_dirs=[str(Path(sys.prefix) / "share" / "jupyter" / "kernels")])
    manager = KernelManager(kernel_name="python3", kernel_spec_manager=specs)
    assert manager.format_kernel_cmd()[0] == sys.executable
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    # One more cell, to learn the kernel's embedded yarfd.
    notebook.cells.append(nbformat.v4.new_code_cell("print(yarf.embedded_server().pid)"))
    runner = nbclient.NotebookClient(
        notebook,
        km=manager,
        timeout=300,
        resources={"metadata": {"path": str(NOTEBOOK.parent)}},
    )
    try:
        runner.execute()
    finally:
        # A client given its kernel manager leaves the kernel to it: a
        # graceful shutdown, so that the kernel's exit stops its yarfd.
        if manager.has_kernel:
            manager.shutdown_kernel()
    *cells, probe = notebook.cells
    outputs = [output for cell in cells for output in cell.get("outputs", [])]
    assert not [output for output in outputs if output.output_type == "error"]
    assert any("image/png" in output.get("data", {}) for output in outputs)
    pid = int(probe.outputs[0].text)
    cmdline = Path(f"/proc/{pid}/cmdline")
    assert not cmdline.exists() or b"yarfd" not in cmdline.read_bytes()
