"""The job verbs of the `yarf` command against the session's real yarfd.

Each verb runs in process through ``yarf.cli.main`` (the same code as the
installed command), its output captured.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Callable
from pathlib import Path

import grpc
import pytest
from conftest import small_scene

from yarf import Client, LocalServer
from yarf.cli import main
from yarf.scene import write_scene
from yarf.v1 import render_pb2, scene_pb2

# A film that is not square, so that width and height cannot be swapped unseen.
WIDTH, HEIGHT = 24, 16
# Far more samples than the tests wait for: the job runs until cancelled.
ENDLESS_SPP = 1_000_000
MISSING_JOB = "job-999999"
IMPORT_SCENES = Path(__file__).parent / "scenes" / "import"
CREDENTIAL_VARIABLES = ("YARF_TOKEN", "YARF_TLS_CA")

Yarf = Callable[..., tuple[int, str, str]]


@pytest.fixture
def yarf(
    server: LocalServer, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> Yarf:
    """Runs ``yarf VERB ARGS... --server ADDRESS``; returns the exit code, stdout, stderr."""
    # The session's yarfd is plaintext loopback: no credentials of the environment apply.
    for variable in CREDENTIAL_VARIABLES:
        monkeypatch.delenv(variable, raising=False)

    def run(*args: str) -> tuple[int, str, str]:
        capsys.readouterr()
        code = main([*args, "--server", server.address])
        out, err = capsys.readouterr()
        return code, out, err

    return run


def scene_file(folder: Path, scene: scene_pb2.Scene, name: str = "scene.json") -> Path:
    path = folder / name
    write_scene(scene, path)
    return path


def film_scene(size: tuple[int, int] = (WIDTH, HEIGHT)) -> scene_pb2.Scene:
    scene = small_scene()
    scene.film.width, scene.film.height = size
    return scene


def submit(yarf: Yarf, path: Path, *options: str) -> str:
    code, out, err = yarf("submit", str(path), *options)
    assert code == 0, err
    job_id = out.strip()
    assert job_id.startswith("job-"), out
    return job_id


def wait_until_running(client: Client, job_id: str, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        status = client.status(job_id)
        if status.state == render_pb2.RUNNING and status.samples_done > 0:
            return
        assert status.state in (render_pb2.QUEUED, render_pb2.RUNNING), status
        time.sleep(0.05)
    raise AssertionError(f"job {job_id} did not start rendering within {timeout} s")


def image_size(path: Path) -> tuple[int, int]:
    """Width and height of an EXR or PNG file: by OpenImageIO when it is installed,
    else from the file's header (the PNG IHDR chunk, the EXR dataWindow attribute)."""
    try:
        import OpenImageIO as oiio  # optional: not every machine has it
    except ImportError:
        return _header_size(path.read_bytes())
    image = oiio.ImageInput.open(str(path))
    assert image is not None, oiio.geterror()
    try:
        spec = image.spec()
        assert image.read_image() is not None, image.geterror()
        return spec.width, spec.height
    finally:
        image.close()


def _header_size(data: bytes) -> tuple[int, int]:
    if data.startswith(b"\x89PNG\r\n\x1a\n"):
        assert data[12:16] == b"IHDR" and data.endswith(b"IEND\xaeB`\x82"), "truncated PNG"
        width, height = struct.unpack(">II", data[16:24])
        return width, height
    assert data.startswith(b"\x76\x2f\x31\x01"), "neither a PNG nor an EXR file"
    # EXR attributes follow the magic and version: name\0 type\0 size value, until an empty name.
    at = 8
    while data[at] != 0:
        name_end = data.index(b"\0", at)
        type_end = data.index(b"\0", name_end + 1)
        (size,) = struct.unpack("<i", data[type_end + 1 : type_end + 5])
        value = data[type_end + 5 : type_end + 5 + size]
        if data[at:name_end] == b"dataWindow":
            x0, y0, x1, y1 = struct.unpack("<4i", value)
            return x1 - x0 + 1, y1 - y0 + 1
        at = type_end + 5 + size
    raise AssertionError("EXR header without dataWindow")


def test_submit_watch_and_fetch_write_images_of_the_films_size(
    yarf: Yarf, client: Client, tmp_path: Path
) -> None:
    job_id = submit(yarf, scene_file(tmp_path, film_scene()), "--spp", "8", "--name", "verbs")

    code, out, err = yarf("watch", job_id)
    assert code == 0, err
    assert f"job {job_id} SUCCEEDED" in out
    assert "8/8 spp" in err  # the progress bar

    for name in ("out.exr", "out.png"):
        code, out, err = yarf("fetch", job_id, "-o", str(tmp_path / name))
        assert code == 0, err
        assert image_size(tmp_path / name) == (WIDTH, HEIGHT), name

    code, out, _ = yarf("status", job_id)
    assert code == 0
    assert "SUCCEEDED" in out and "verbs" in out and "8/8 spp" in out
    assert client.status(job_id).name == "verbs"


def test_submit_with_watch_exits_zero_when_the_job_succeeds(yarf: Yarf, tmp_path: Path) -> None:
    code, out, err = yarf(
        "submit", str(scene_file(tmp_path, film_scene())), "--spp", "4", "--watch"
    )
    assert code == 0, err
    job_id, verdict = out.splitlines()[:2]
    assert verdict.startswith(f"job {job_id} SUCCEEDED"), out


@pytest.mark.parametrize("name", ["mitsuba_camera.xml", "pbrt_basic.pbrt"])
def test_submit_imports_mitsuba_and_pbrt_scenes_as_render_does(yarf: Yarf, name: str) -> None:
    code, out, err = yarf("submit", str(IMPORT_SCENES / name), "--spp", "2", "--watch", "-q")
    assert code == 0, err
    job_id, verdict = out.splitlines()[:2]
    assert verdict.startswith(f"job {job_id} SUCCEEDED"), out


def test_watch_of_a_failing_job_exits_non_zero_with_its_error(
    yarf: Yarf, client: Client, tmp_path: Path
) -> None:
    scene = film_scene()
    garbage = scene.shapes.add(name="garbage_mesh", material="grey")
    garbage.mesh.data = b"v zero 0 0\nf 1 2 3\nthis is not an OBJ file\n"
    garbage.mesh.format = "obj"
    job_id = submit(yarf, scene_file(tmp_path, scene), "--max-retries", "1")

    code, _, err = yarf("watch", job_id)
    assert code != 0
    assert f"job {job_id} FAILED" in err and "garbage_mesh" in err, err
    # It failed twice: once, and once more after its one retry.
    assert client.status(job_id).attempts == 2


def test_cancel_stops_a_long_job_and_list_shows_it_cancelled(
    yarf: Yarf, client: Client, tmp_path: Path
) -> None:
    path = scene_file(tmp_path, film_scene((64, 64)))
    job_id = submit(yarf, path, "--spp", str(ENDLESS_SPP), "--name", "endless")
    wait_until_running(client, job_id)

    code, out, err = yarf("cancel", job_id)
    assert code == 0, err
    assert job_id in out
    assert client.wait(job_id, timeout=10).state == render_pb2.CANCELLED

    code, _, err = yarf("watch", job_id, "--quiet")
    assert code != 0 and f"job {job_id} CANCELLED" in err, err

    code, out, err = yarf("list")
    assert code == 0, err
    header, *rows = out.splitlines()
    assert header.split() == ["JOB", "NAME", "OWNER", "STATE", "PRIORITY", "PROGRESS"]
    row = next(row for row in rows if row.startswith(job_id)).split()
    # id, name, owner ("local" on loopback), state, the default priority, progress.
    assert row[:5] == [job_id, "endless", "local", "CANCELLED", "50"], row


def test_list_shows_names_without_their_control_characters(yarf: Yarf, tmp_path: Path) -> None:
    job_id = submit(yarf, scene_file(tmp_path, film_scene()), "--spp", "1", "--name", "a\x1b[2Jb")
    code, out, _ = yarf("list")
    assert code == 0
    row = next(row for row in out.splitlines() if row.startswith(job_id))
    assert "\x1b" not in out and "a?[2Jb" in row, row


def test_priority_changes_the_priority_of_a_job(yarf: Yarf, client: Client, tmp_path: Path) -> None:
    with pytest.raises(grpc.RpcError) as error:
        client.set_priority(MISSING_JOB, 50)
    assert error.value.code() == grpc.StatusCode.NOT_FOUND, error.value
    path = scene_file(tmp_path, film_scene((64, 64)))
    job_id = submit(yarf, path, "--spp", str(ENDLESS_SPP), "--priority", "20")
    try:
        assert client.status(job_id).priority == 20

        code, out, err = yarf("priority", job_id, "90")
        assert code == 0, err
        assert f"job {job_id} priority 90" in out
        assert client.status(job_id).priority == 90
        code, out, _ = yarf("status", job_id)
        assert any(line.split() == ["priority", "90"] for line in out.splitlines()), out

        code, _, err = yarf("priority", job_id, "101")
        assert code == 2 and "1 to 100" in err
    finally:
        client.cancel(job_id)

    # An ended job has no place in the queue to move to.
    assert client.wait(job_id, timeout=10).state == render_pb2.CANCELLED
    code, _, err = yarf("priority", job_id, "60")
    assert code != 0 and "FAILED_PRECONDITION" in err, err


@pytest.mark.parametrize(
    "verb", [["status"], ["watch"], ["cancel"], ["fetch", "-o", "out.png"], ["priority", "50"]]
)
def test_an_unknown_job_id_is_a_clear_error(
    yarf: Yarf, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, verb: list[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    name, *rest = verb
    code, out, err = yarf(name, MISSING_JOB, *rest)
    assert code != 0
    assert f"no job {MISSING_JOB!r}" in err, err
    assert "Traceback" not in err and not out
    assert not (tmp_path / "out.png").exists()


def test_fetch_refuses_an_image_format_it_cannot_write(yarf: Yarf, tmp_path: Path) -> None:
    job_id = submit(yarf, scene_file(tmp_path, film_scene()), "--spp", "1")
    code, _, err = yarf("fetch", job_id, "-o", str(tmp_path / "out.jpg"))
    assert code == 2 and ".exr, .png" in err, err


def test_submit_warns_of_a_sample_count_its_sobol_sampler_is_not_best_at(
    yarf: Yarf, tmp_path: Path
) -> None:
    path = scene_file(tmp_path, film_scene())
    code, out, err = yarf("submit", str(path), "--spp", "12")
    assert code == 0, err
    assert out.strip().startswith("job-")
    assert "warning: sampler 'sobol' works best with a power of two" in err
    assert "use 8 or 16" in err
    code, _, err = yarf("submit", str(path), "--spp", "16")
    assert code == 0 and "warning" not in err, err
