"""AOVs from the command line and yarf.render, the client's denoiser, and an
embedded yarfd that does not outlive the process that started it.

Commands run in process through ``yarf.cli.main`` against the session's
yarfd. The denoiser's test compares against a long render of the same
scene: its figure is the RMSE of display values (radiance clamped at 1),
since the light's own pixels, about 18 times brighter than any lit wall,
would otherwise outweigh every other pixel.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable
from pathlib import Path

import grpc
import numpy as np
import OpenImageIO as oiio
import pytest
from conftest import CORNELL_BOX, small_scene

import yarf
from yarf import Client, LocalServer
from yarf.cli import main
from yarf.denoise import denoise
from yarf.render_options import AOV_NAMES, OptionError
from yarf.scene import load_scene, write_scene

Yarf = Callable[..., tuple[int, str, str]]
SIZE = 16


@pytest.fixture
def yarf_cli(
    server: LocalServer, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> Yarf:
    """Runs ``yarf ARGS... --server ADDRESS`` in process; returns the exit code, stdout, stderr."""
    for variable in ("YARF_TOKEN", "YARF_TLS_CA"):
        monkeypatch.delenv(variable, raising=False)

    def run(*args: str) -> tuple[int, str, str]:
        capsys.readouterr()
        try:
            code = main([*args, "--server", server.address])
        except SystemExit as exit:
            code = int(exit.code or 0)
        out, err = capsys.readouterr()
        return code, out, err

    return run


@pytest.fixture
def scene_path(tmp_path: Path) -> Path:
    path = tmp_path / "scene.json"
    write_scene(small_scene(SIZE), path)
    return path


def job_of(out: str) -> str:
    """The job id ``yarf render`` prints in its last line."""
    found = re.search(r"job (\S+)\)", out)
    assert found, out
    return found.group(1)


def exr_channels(path: Path) -> tuple[list[str], np.ndarray, int]:
    """The channel names, the pixels [H, W, channels] as float32, and the file's format."""
    image = oiio.ImageInput.open(str(path))
    assert image is not None, oiio.geterror()
    try:
        spec = image.spec()
        pixels = np.asarray(image.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT))
        return list(spec.channelnames), pixels.reshape(spec.height, spec.width, -1), spec.format
    finally:
        image.close()


def layer(names: list[str], pixels: np.ndarray, name: str) -> np.ndarray:
    return pixels[..., [names.index(f"{name}.{c}") for c in "RGB"]]


def test_the_client_knows_the_servers_aov_names(client: Client) -> None:
    with pytest.raises(grpc.RpcError) as refused:
        client.submit(small_scene(SIZE), 1, aovs=["no_such_output"])
    listed = re.search(r"is not one of ([a-z_, ]+)", refused.value.details())
    assert listed, refused.value.details()
    assert tuple(listed.group(1).split(", ")) == AOV_NAMES


def test_render_writes_the_aovs_as_exr_channels_after_rgb(
    yarf_cli: Yarf, client: Client, scene_path: Path, tmp_path: Path
) -> None:
    output = tmp_path / "out.exr"
    code, out, err = yarf_cli(
        "render", str(scene_path), "--spp", "4", "--aov", "albedo,depth", "-q", "-o", str(output)
    )
    assert code == 0, err
    names, pixels, file_format = exr_channels(output)
    raw = client.raw(job_of(out))
    assert names == ["R", "G", "B"] + [f"{n}.{c}" for n in raw.aovs for c in "RGB"]
    assert sorted(raw.aovs) == ["albedo", "depth"]
    assert file_format == oiio.FLOAT
    np.testing.assert_array_equal(pixels[..., :3], raw.pixels)
    for name, image in raw.aovs.items():
        np.testing.assert_array_equal(layer(names, pixels, name), image, err_msg=name)
    assert raw.aovs["depth"].max() > 0


def test_half_exr_holds_the_aovs_as_halves_and_png_the_image_alone(
    yarf_cli: Yarf, client: Client, scene_path: Path, tmp_path: Path
) -> None:
    half, png = tmp_path / "half.exr", tmp_path / "out.png"
    code, out, err = yarf_cli(
        "render", str(scene_path), "--spp", "2", "--aov", "uv", "--half", "-q", "-o", str(half)
    )
    assert code == 0, err
    names, pixels, file_format = exr_channels(half)
    assert file_format == oiio.HALF
    uv = client.raw(job_of(out)).aovs["uv"]
    np.testing.assert_array_equal(layer(names, pixels, "uv"), uv.astype(np.float16))
    code, _, err = yarf_cli(
        "render", str(scene_path), "--spp", "2", "--aov", "uv", "-q", "-o", str(png)
    )
    assert code == 0, err
    assert exr_channels(png)[0] == ["R", "G", "B"]


@pytest.mark.parametrize(
    ("aov", "message"),
    [
        ("albedo,dpth", "--aov: unknown output 'dpth' (did you mean 'depth'?"),
        ("normals", "--aov: unknown output 'normals' (did you mean 'sh_normal'?"),
        ("uv,uv", "--aov: 'uv' is named twice"),
        ("albedo,,depth", "--aov: expected names separated by commas"),
    ],
)
@pytest.mark.parametrize("verb", ["render", "submit"])
def test_a_bad_aov_is_one_line_and_exit_2_before_anything_renders(
    yarf_cli: Yarf,
    client: Client,
    scene_path: Path,
    tmp_path: Path,
    verb: str,
    aov: str,
    message: str,
) -> None:
    jobs = len(client.list())
    output = ["-o", str(tmp_path / "out.exr")] if verb == "render" else []
    code, out, err = yarf_cli(verb, str(scene_path), "--aov", aov, *output)
    assert code == 2
    assert err.count("\n") == 1 and message in err, err
    assert out == "" and not (tmp_path / "out.exr").exists()
    assert len(client.list()) == jobs


def test_submit_asks_for_the_aovs_and_fetch_writes_them(
    yarf_cli: Yarf, client: Client, scene_path: Path, tmp_path: Path
) -> None:
    code, out, err = yarf_cli(
        "submit", str(scene_path), "--spp", "2", "--aov", "shape_index", "--watch", "-q"
    )
    assert code == 0, err
    job = out.splitlines()[0]
    output = tmp_path / "fetched.exr"
    code, _, err = yarf_cli("fetch", job, "-o", str(output))
    assert code == 0, err
    names, pixels, _ = exr_channels(output)
    assert names == ["R", "G", "B", "shape_index.R", "shape_index.G", "shape_index.B"]
    np.testing.assert_array_equal(
        layer(names, pixels, "shape_index"), client.raw(job).aovs["shape_index"]
    )


def test_yarf_render_fills_image_aovs(client: Client, tmp_path: Path) -> None:
    image = yarf.render(small_scene(SIZE), spp=4, seed=2, aovs=["depth", "albedo"], server=client)
    assert sorted(image.aovs) == ["albedo", "depth"]
    for values in image.aovs.values():
        assert values.shape == image.shape and values.dtype == np.float32
    assert image.aovs["depth"].max() > 0
    # Saved, the EXR holds them too.
    image.save(tmp_path / "image.exr")
    names, pixels, _ = exr_channels(tmp_path / "image.exr")
    np.testing.assert_array_equal(layer(names, pixels, "depth"), image.aovs["depth"])


def test_client_render_refuses_an_unknown_aov_before_submitting(client: Client) -> None:
    jobs = len(client.list())
    with pytest.raises(OptionError, match="did you mean 'albedo'"):
        client.render(small_scene(SIZE), 1, aovs=["albedos"])
    with pytest.raises(OptionError, match="did you mean 'position'"):
        yarf.render(small_scene(SIZE), spp=1, aovs="positon", server=client)
    assert len(client.list()) == jobs


def display_rmse(image: np.ndarray, reference: np.ndarray) -> float:
    clamp = np.minimum(image.astype(np.float64), 1.0)
    return float(np.sqrt(np.mean((clamp - np.minimum(reference, 1.0)) ** 2)))


def test_the_denoiser_reduces_the_error_of_a_16_spp_cornell_box(client: Client) -> None:
    # Measured on this 64×64 film against 512 spp: the denoised image's RMSE is
    # 1.4 to 1.8 times smaller, seed by seed; pooled over three seeds, about 1.7.
    scene = load_scene(CORNELL_BOX)
    reference = yarf.render(scene, spp=512, seed=1, res=(64, 64), server=client).pixels
    raw_squares, denoised_squares = [], []
    for seed in (2, 3, 4):
        image = yarf.render(scene, spp=16, seed=seed, res=(64, 64), denoise=True, server=client)
        assert image.raw is not None and sorted(image.aovs) == ["albedo", "sh_normal"]
        raw_squares.append(display_rmse(image.raw, reference) ** 2)
        denoised_squares.append(display_rmse(image.pixels, reference) ** 2)
    ratio = np.sqrt(np.mean(raw_squares) / np.mean(denoised_squares))
    assert ratio > 1.3, f"the denoiser reduced the RMSE {ratio:.2f} times"


def test_the_denoiser_leaves_a_flat_image_nearly_unchanged() -> None:
    # A white furnace: every pixel the same radiance, albedo and normal.
    rng = np.random.default_rng(1)
    flat = np.full((64, 64, 3), 0.75, np.float32)
    aovs = {"albedo": np.full_like(flat, 0.8), "sh_normal": np.zeros_like(flat)}
    aovs["sh_normal"][..., 2] = 1.0
    change = np.abs(denoise(flat, aovs) / flat - 1)
    # Within 1% away from the border; OIDN's few pixels at the very edge move most
    # (up to about 20% in a corner), and the mean by a fraction of a percent.
    assert change[4:-4, 4:-4].max() < 0.01
    assert change.mean() < 0.005 and np.percentile(change, 99) < 0.03
    # With a little noise, the mean stays and the noise goes down.
    noisy = flat * (1 + 0.05 * rng.standard_normal(flat.shape)).astype(np.float32)
    denoised = denoise(noisy, aovs)
    assert abs(denoised.mean() - noisy.mean()) < 0.01 * noisy.mean()
    assert np.std(denoised) < 0.5 * np.std(noisy)


def test_render_denoise_writes_the_denoised_image_and_the_server_keeps_the_raw(
    yarf_cli: Yarf, client: Client, tmp_path: Path
) -> None:
    output = tmp_path / "denoised.exr"
    code, out, err = yarf_cli(
        "render", str(CORNELL_BOX), "--res", "32x32", "--spp", "4", "--denoise", "-q",
        "-o", str(output),
    )  # fmt: skip
    assert code == 0, err
    names, pixels, _ = exr_channels(output)
    raw = client.raw(job_of(out))
    assert names[3:] == [f"{n}.{c}" for n in ("albedo", "sh_normal") for c in "RGB"]
    np.testing.assert_allclose(pixels[..., :3], denoise(raw.pixels, raw.aovs), rtol=1e-5, atol=1e-6)
    assert not np.allclose(pixels[..., :3], raw.pixels)


def test_fetch_denoise_of_a_job_without_albedo_and_normal_is_one_line(
    yarf_cli: Yarf, scene_path: Path, tmp_path: Path
) -> None:
    code, out, err = yarf_cli("submit", str(scene_path), "--spp", "1", "--watch", "-q")
    assert code == 0, err
    code, _, err = yarf_cli(
        "fetch", out.splitlines()[0], "--denoise", "-o", str(tmp_path / "x.exr")
    )
    assert code == 1
    assert err.count("\n") == 1 and "no albedo and sh_normal AOV" in err, err


def test_a_missing_denoiser_is_one_line_before_anything_renders(
    yarf_cli: Yarf,
    client: Client,
    scene_path: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "pyoidn", None)  # import pyoidn fails
    jobs = len(client.list())
    code, _, err = yarf_cli("render", str(scene_path), "--denoise", "-o", str(tmp_path / "x.exr"))
    assert code == 1
    assert err.count("\n") == 1 and "pip install 'yarf[denoise]'" in err, err
    assert len(client.list()) == jobs


def _is_gone(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return True
    return state in ("Z", "X")  # a zombie no one reaped has ended too


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_an_embedded_yarfd_dies_with_the_process_that_started_it() -> None:
    program = textwrap.dedent(
        """
        import time
        from yarf import LocalServer
        server = LocalServer()
        server.start()
        print(server.pid, flush=True)
        time.sleep(120)
        """
    )
    parent = subprocess.Popen(
        [sys.executable, "-c", program], stdout=subprocess.PIPE, env=dict(os.environ), text=True
    )
    try:
        assert parent.stdout is not None
        yarfd = int(parent.stdout.readline())
        assert not _is_gone(yarfd)
        parent.send_signal(signal.SIGKILL)
        parent.wait(10)
        deadline = time.monotonic() + 10
        while not _is_gone(yarfd) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert _is_gone(yarfd), f"yarfd {yarfd} outlived the process that started it"
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()
