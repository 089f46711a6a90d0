"""The render and image options shared by `yarf render`, `yarf submit` and
Client.render, and the command's behaviour when things go wrong.

Commands run in process through ``yarf.cli.main`` against the session's
yarfd, except where the test needs a real process (a closed stdout).
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from conftest import small_scene

from yarf import Client, LocalServer, cli
from yarf.cli import main
from yarf.images import display_linear
from yarf.render_options import OptionError
from yarf.scene import write_scene
from yarf.v1 import render_pb2, scene_pb2

# A film that is not square, so that width and height cannot be swapped unseen.
WIDTH, HEIGHT = 24, 16
PBRT_SCENE = Path(__file__).parent / "scenes" / "import" / "pbrt_basic.pbrt"
CREDENTIAL_VARIABLES = ("YARF_TOKEN", "YARF_TLS_CA")

Yarf = Callable[..., tuple[int, str, str]]


@pytest.fixture
def yarf(
    server: LocalServer, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> Yarf:
    """Runs ``yarf ARGS... --server ADDRESS`` in process; returns the exit code, stdout, stderr."""
    for variable in CREDENTIAL_VARIABLES:
        monkeypatch.delenv(variable, raising=False)

    def run(*args: str, server_address: str | None = None) -> tuple[int, str, str]:
        capsys.readouterr()
        try:
            code = main([*args, "--server", server_address or server.address])
        except SystemExit as exit:  # argparse's errors, its one line already written
            code = int(exit.code or 0)
        out, err = capsys.readouterr()
        return code, out, err

    return run


@pytest.fixture
def scene_path(tmp_path: Path) -> Path:
    scene = small_scene()
    scene.film.width, scene.film.height = WIDTH, HEIGHT
    path = tmp_path / "scene.json"
    write_scene(scene, path)
    return path


def read_image(path: Path) -> tuple[oiio.ImageSpec, np.ndarray]:
    """The file's spec and its pixels as OpenImageIO reads them (floats in [0, 1] for PNG)."""
    image = oiio.ImageInput.open(str(path))
    assert image is not None, oiio.geterror()
    try:
        spec = image.spec()
        pixels = image.read_image(oiio.FLOAT)
        assert pixels is not None, image.geterror()
        return spec, np.asarray(pixels)
    finally:
        image.close()


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    return np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)


# Each bad invocation: the verb and its options ({dir}: a temporary folder,
# {scene}: a small 24x16 scene file), a fragment of the one-line message.
BAD_INVOCATIONS: list[tuple[str, list[str], str]] = [
    ("render", ["--spp", "0"], "--spp: must be 1 to 1048576, not 0"),
    ("render", ["--spp", "-1"], "--spp: must be 1 to 1048576, not -1"),
    ("render", ["--spp", "2000000"], "--spp: must be 1 to 1048576"),
    ("render", ["--spp", "many"], "argument --spp: invalid int value: 'many'"),
    ("render", ["--seed", "-3"], "--seed: must be 0 to 2^64 - 1"),
    ("render", ["--res", "64"], "--res: expected WIDTHxHEIGHT"),
    ("render", ["--res", "0x10"], "--res: each side must be 1 to 16384 pixels, not 0x10"),
    ("render", ["--res", "16384x16384"], "--res: 16384x16384 has more than 2^26"),
    ("render", ["--crop", "1,2,3"], "--crop: expected x0,x1,y0,y1"),
    ("render", ["--crop", "a,b,c,d"], "--crop: expected four numbers"),
    ("render", ["--crop", "10,5,0,4"], "--crop: [10, 5) x [0, 4) is not a window of the 24x16"),
    ("render", ["--crop", "0,30,0,4"], "is not a window of the 24x16 film"),
    ("render", ["--res", "8x8", "--crop", "0,12,0,4"], "is not a window of the 8x8 film"),
    ("render", ["--crop", "0,0.5,0,1.5"], "--crop: fractions of the film must lie in [0, 1]"),
    ("render", ["--time-limit", "0"], "--time-limit: must be a positive number of seconds"),
    ("render", ["--time-limit", "nan"], "--time-limit: must be a positive number of seconds"),
    ("render", ["--time-limit", "soon"], "argument --time-limit: invalid float value"),
    ("render", ["--max-depth", "-2"], "--max-depth: must be -1 (unbounded) or at least 0"),
    ("render", ["--transport", "@127.0.0.1:1"], "--transport: expected CLASS or CLASS@ADDRESS"),
    ("render", ["--material", "grey"], "--material: expected NAME=CLASS[@ADDRESS]"),
    ("render", ["--material", "nosuch=plastic"], "no material or material class of that name"),
    ("render", ["--threads", "0"], "--threads: must be 1 to 65536, not 0"),
    ("render", ["-D", "res=3"], "-D sets parameters of Mitsuba scenes only"),
    ("render", ["-o", "{dir}/out.tif"], "the output's extension must be one of .exr, .png"),
    ("render", ["-o", "{dir}/out.png", "--half"], "--half: applies to EXR images"),
    ("render", ["--exposure", "1"], "--exposure: applies to PNG images"),
    ("render", ["--tonemap", "aces"], "--tonemap: applies to PNG images"),
    ("render", ["-o", "{dir}/out.png", "--exposure", "inf"], "--exposure: must be a finite"),
    ("render", ["-o", "{dir}/out.png", "--tonemap", "reinhard"], "invalid choice: 'reinhard'"),
    ("render", ["-o", "{scene}/out.exr"], "cannot write"),
    ("render", ["-o", "{dir}"], "cannot write"),
    ("submit", ["--spp", "0"], "--spp: must be 1 to 1048576, not 0"),
    ("submit", ["--res", "wide"], "--res: expected WIDTHxHEIGHT"),
    ("submit", ["--crop", "0,30,0,4"], "is not a window of the 24x16 film"),
    ("submit", ["--time-limit", "3"], "--time-limit needs --watch"),
    ("submit", ["--priority", "0"], "--priority must be 1 to 100"),
    ("submit", ["--max-depth", "-5"], "--max-depth: must be -1 (unbounded) or at least 0"),
    ("submit", ["--threads", "-1"], "--threads: must be 1 to 65536, not -1"),
]


@pytest.mark.parametrize(
    ("verb", "options", "message"),
    BAD_INVOCATIONS,
    ids=[f"{verb} {' '.join(options)}" for verb, options, _ in BAD_INVOCATIONS],
)
def test_a_bad_value_is_one_line_and_exit_2_before_anything_renders(
    yarf: Yarf,
    client: Client,
    tmp_path: Path,
    scene_path: Path,
    verb: str,
    options: list[str],
    message: str,
) -> None:
    arguments = [option.format(dir=tmp_path, scene=scene_path) for option in options]
    if verb == "render" and "-o" not in arguments:
        arguments += ["-o", str(tmp_path / "out.exr")]
    jobs_before = len(client.list())
    code, _, err = yarf(verb, str(scene_path), *arguments)
    assert code == 2, err
    assert message in err, err
    assert len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err
    assert len(client.list()) == jobs_before, "a job was submitted"
    assert not list(tmp_path.glob("out.*"))


def test_fetch_refuses_image_options_its_format_ignores(yarf: Yarf, tmp_path: Path) -> None:
    code, _, err = yarf("fetch", "job-000001", "-o", str(tmp_path / "out.png"), "--half")
    assert code == 2 and "--half: applies to EXR images" in err, err


@pytest.mark.parametrize("format", ["json", "pbrt"])
def test_res_sets_the_film_size_of_every_scene_format(
    yarf: Yarf, tmp_path: Path, scene_path: Path, format: str
) -> None:
    source = scene_path if format == "json" else PBRT_SCENE
    output = tmp_path / "out.exr"
    code, _, err = yarf("render", str(source), "-o", str(output), "--spp", "1", "--res", "40x12")
    assert code == 0, err
    spec, pixels = read_image(output)
    assert (spec.width, spec.height) == (40, 12)
    assert np.isfinite(pixels).all()


def test_crop_renders_only_the_window(
    yarf: Yarf, client: Client, tmp_path: Path, scene_path: Path
) -> None:
    whole, window = tmp_path / "whole.exr", tmp_path / "window.exr"
    common = ["--spp", "8", "--seed", "5", "-q"]
    assert yarf("render", str(scene_path), "-o", str(whole), *common)[0] == 0
    code, _, err = yarf(
        "render", str(scene_path), "-o", str(window), *common, "--crop", "4,20,2,10"
    )
    assert code == 0, err
    spec, pixels = read_image(window)
    # The window alone, placed in the whole film as pbrt places a crop.
    assert (spec.width, spec.height, spec.x, spec.y) == (16, 8, 4, 2)
    assert (spec.full_width, spec.full_height) == (WIDTH, HEIGHT)
    # A crop takes the same samples as the whole render does for its pixels.
    _, full = read_image(whole)
    np.testing.assert_array_equal(pixels, full[2:10, 4:20])
    assert client.list()[0].samples_total == 8

    # A submitted crop job, fetched later, is written as `render` writes it.
    job_id = client.list()[0].job_id
    fetched = tmp_path / "fetched.exr"
    assert client.wait(job_id).state == render_pb2.SUCCEEDED
    code, _, err = yarf("fetch", job_id, "-o", str(fetched))
    assert code == 0, err
    spec, again = read_image(fetched)
    assert (spec.width, spec.height, spec.x, spec.y) == (16, 8, 4, 2)
    np.testing.assert_array_equal(again, pixels)

    result = client.render(small_scene(), spp=4, seed=5, crop=(0.25, 0.75, 0.0, 0.5))
    assert result.pixels.shape == (8, 8, 3)


@pytest.mark.parametrize(
    ("film", "window"),
    [
        ('"float cropwindow" [0.75 0.25 0 0.5]', (16, 8, 8, 0)),  # fractions, edges rounded up
        ('"integer pixelbounds" [3 11 4 9]', (8, 5, 3, 4)),
    ],
)
def test_a_pbrt_files_crop_is_what_render_renders_unless_crop_is_given(
    yarf: Yarf,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    film: str,
    window: tuple[int, int, int, int],
) -> None:
    path = tmp_path / "cropped.pbrt"
    path.write_text(
        'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\n'
        f'Film "rgb" "integer xresolution" 32 "integer yresolution" 16 {film}\n'
        'WorldBegin\nLightSource "infinite" "rgb L" [1 1 1]\nShape "sphere"\n'
    )
    output = tmp_path / "cropped.exr"
    code, _, err = yarf("render", str(path), "-o", str(output), "--spp", "2", "-q")
    assert code == 0, err
    spec, _ = read_image(output)
    assert (spec.width, spec.height, spec.x, spec.y) == window
    assert (spec.full_width, spec.full_height) == (32, 16)
    # --crop wins over the file's, as pbrt's command line does.
    code, _, err = yarf(
        "render", str(path), "-o", str(output), "--spp", "2", "-q", "--crop", "0,32,0,16"
    )
    assert code == 0, err
    spec, _ = read_image(output)
    assert (spec.width, spec.height) == (32, 16)
    # yarf convert says what the file asks for.
    capsys.readouterr()
    assert main(["convert", str(path), str(tmp_path / "cropped.json")]) == 0
    assert "it renders only --crop" in capsys.readouterr().out


def test_time_limit_ends_early_with_a_valid_image(
    yarf: Yarf, client: Client, tmp_path: Path, scene_path: Path
) -> None:
    output = tmp_path / "limited.exr"
    started = time.monotonic()
    code, out, err = yarf(
        "render", str(scene_path), "-o", str(output), "--spp", "1000000", "--res", "64x64",
        "--time-limit", "1.5", "-q",
    )  # fmt: skip
    took = time.monotonic() - started
    assert code == 0, err
    assert "stopped at the time limit" in out
    assert 1.5 <= took < 20, f"took {took:.1f} s"
    status = client.list()[0]
    assert status.state == render_pb2.CANCELLED and 0 < status.samples_done < 1000000
    _, limited = read_image(output)
    scene = small_scene(64)
    reference = client.render(scene, spp=64, seed=1).pixels
    # Every pixel an estimate of the same image: finite, and the same mean within noise.
    assert limited.shape == (64, 64, 3) and np.isfinite(limited).all() and limited.min() >= 0
    assert abs(limited.mean() - reference.mean()) < 0.05 * reference.mean()

    result = client.render(scene, spp=1000000, time_limit=1.0)
    assert result.status.state == render_pb2.CANCELLED and result.status.samples_done > 0


def test_exr_is_float32_by_default_and_half_on_request(
    yarf: Yarf, client: Client, tmp_path: Path, scene_path: Path
) -> None:
    full, half = tmp_path / "full.exr", tmp_path / "half.exr"
    code, out, err = yarf("submit", str(scene_path), "--spp", "4", "--watch", "-q")
    assert code == 0, err
    job_id = out.splitlines()[0]
    assert yarf("fetch", job_id, "-o", str(full))[0] == 0
    assert yarf("fetch", job_id, "-o", str(half), "--half")[0] == 0
    full_spec, full_pixels = read_image(full)
    half_spec, half_pixels = read_image(half)
    assert full_spec.format == oiio.FLOAT
    assert half_spec.format == oiio.HALF
    pixels = client.image(job_id)
    np.testing.assert_array_equal(full_pixels, pixels)
    np.testing.assert_array_equal(half_pixels, pixels.astype(np.float16).astype(np.float32))


def test_exposure_doubles_linear_values_before_the_png_transfer(
    yarf: Yarf, client: Client, tmp_path: Path, scene_path: Path
) -> None:
    code, out, err = yarf("submit", str(scene_path), "--spp", "4", "--watch", "-q")
    assert code == 0, err
    job_id = out.splitlines()[0]
    brighter = tmp_path / "brighter.png"
    assert yarf("fetch", job_id, "-o", str(brighter), "--exposure", "+1")[0] == 0
    spec, encoded = read_image(brighter)
    assert spec.format == oiio.UINT8
    expected = np.clip(2.0 * client.image(job_id), 0.0, 1.0)
    # Within the 8-bit quantisation of the sRGB values.
    decoded = srgb_decode(encoded)
    step = srgb_decode(np.clip(encoded + 0.5 / 255, 0, 1)) - srgb_decode(encoded - 0.5 / 255)
    assert (np.abs(decoded - expected) <= step + 1e-6).all()


def test_aces_maps_bright_values_below_one() -> None:
    bright = np.array([[[0.5] * 3, [1.0] * 3, [2.0] * 3, [4.0] * 3, [8.0] * 3]], np.float32)
    aces = display_linear(bright, tonemap="aces")[0, :, 0]
    linear = display_linear(bright)[0, :, 0]
    assert (aces < 1.0).all() and (np.diff(aces) > 0).all(), aces
    np.testing.assert_array_equal(linear, [0.5, 1, 1, 1, 1])
    np.testing.assert_allclose(display_linear(bright, exposure=1)[0, 0], 1.0)


def test_aces_png_keeps_detail_where_linear_saturates(
    yarf: Yarf, tmp_path: Path, scene_path: Path
) -> None:
    code, out, err = yarf("submit", str(scene_path), "--spp", "4", "--watch", "-q")
    assert code == 0, err
    job_id = out.splitlines()[0]
    linear, aces = tmp_path / "linear.png", tmp_path / "aces.png"
    assert yarf("fetch", job_id, "-o", str(linear), "--exposure", "3")[0] == 0
    assert yarf("fetch", job_id, "-o", str(aces), "--exposure", "3", "--tonemap", "aces")[0] == 0
    assert (read_image(linear)[1] == 1.0).any()
    assert (read_image(aces)[1] < 1.0).all()


def test_client_render_takes_the_options_and_refuses_bad_values_before_submitting(
    client: Client,
) -> None:
    result = client.render(small_scene(), spp=2, res="20x10", max_depth=2)
    assert result.pixels.shape == (10, 20, 3)
    jobs_before = len(client.list())
    for bad in ({"spp": 0}, {"res": (0, 4)}, {"crop": (0, 99, 0, 4)}, {"time_limit": -1.0}):
        with pytest.raises(OptionError):
            client.render(small_scene(), **bad)  # type: ignore[arg-type]
    assert len(client.list()) == jobs_before


def free_address() -> str:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return f"127.0.0.1:{probe.getsockname()[1]}"


@pytest.mark.parametrize(
    "verb", [["list"], ["status", "job-000001"], ["watch", "job-000001"], ["fetch", "job-000001"]]
)
def test_job_verbs_without_a_server_say_how_to_start_one(
    yarf: Yarf, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, verb: list[str]
) -> None:
    monkeypatch.setattr(cli, "CONNECT_TIMEOUT", 0.5)
    address = free_address()
    options = ["-o", str(tmp_path / "out.exr")] if verb[0] == "fetch" else []
    code, _, err = yarf(*verb, *options, server_address=address)
    assert code == 1
    assert f"no yarfd answers at {address}" in err and f"yarfd --listen {address}" in err, err
    assert len(err.strip().splitlines()) == 1, err


def yarf_command() -> list[str]:
    """The `yarf` console script of the Python environment running the tests."""
    return [str(Path(sys.executable).parent / "yarf")]


def test_list_into_a_closed_pipe_exits_without_a_traceback(
    server: LocalServer, client: Client
) -> None:
    # Enough jobs that the listing is several lines.
    for _ in range(3):
        client.submit(small_scene(), spp=1)
    listing = subprocess.Popen(
        [*yarf_command(), "list", "--server", server.address],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert listing.stdout is not None and listing.stderr is not None
    listing.stdout.close()  # the reader goes away before the table is written
    err = listing.stderr.read().decode()
    assert listing.wait(timeout=60) == 141, err
    assert "Traceback" not in err and "Exception ignored" not in err, err

    piped = subprocess.run(
        f"{' '.join(yarf_command())} list --server {server.address} | head -1",
        shell=True,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert piped.stdout.startswith("JOB"), piped.stdout
    assert "Traceback" not in piped.stderr and "Exception" not in piped.stderr, piped.stderr


def test_a_scene_whose_integrator_cannot_crop_is_refused(yarf: Yarf, tmp_path: Path) -> None:
    scene = small_scene()
    scene.integrator.CopyFrom(scene_pb2.ComponentSpec(class_name="vegas"))
    path = tmp_path / "vegas.json"
    write_scene(scene, path)
    code, _, err = yarf("render", str(path), "-o", str(tmp_path / "out.exr"), "--crop", "0,4,0,4")
    assert code != 0
    assert "crop needs an integrator that renders any range of sample passes" in err, err
    assert "the job's 'vegas' does not" in err, err
