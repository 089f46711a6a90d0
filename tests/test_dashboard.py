"""The web dashboard (`yarf dashboard`) in headless Chromium, against a real yarfd.

The yarfd runs one job at a time (--max-running-jobs 1), so that a second
job stays queued while the first renders. Every page the tests open must
log no console error and raise no script error.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import OpenImageIO as oiio
import pytest
from conftest import small_scene
from playwright.sync_api import BrowserContext, Locator, Page, expect, sync_playwright

from yarf import Client, LocalServer
from yarf.cli import main
from yarf.dashboard import MAX_UPLOAD_BYTES, DashboardServer, find_web_dir
from yarf.v1 import render_pb2, scene_pb2

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
# A film that is not square, so that the preview's width and height cannot be swapped unseen.
WIDTH, HEIGHT = 48, 32
# Far more samples than the tests wait for: the job runs until cancelled.
ENDLESS_SPP = 1_000_000
WAIT_MS = 15_000
ALICE, BOB = "alice-secret", "bob-secret"
AOVS = ["albedo", "sh_normal", "depth"]
VIEWPORT = {"width": 1280, "height": 800}
# A Mitsuba scene of one file, as a browser uploads it: a sphere under an
# emitting rectangle, at 32×24 pixels and 4 samples per pixel.
MITSUBA_SCENE = b"""<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world">
            <lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="32"/>
            <integer name="height" value="24"/>
        </film>
    </sensor>
    <shape type="sphere">
        <float name="radius" value="0.5"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="1.5"/><translate z="-1"/></transform>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
</scene>
"""


@pytest.fixture(scope="module")
def yarfd() -> Iterator[LocalServer]:
    with LocalServer(extra_args=["--max-running-jobs", "1"]) as server:
        yield server


@pytest.fixture(scope="module")
def client(yarfd: LocalServer) -> Iterator[Client]:
    with yarfd.client() as module_client:
        yield module_client


@pytest.fixture(scope="module")
def dashboard(yarfd: LocalServer, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """`yarf dashboard` on a free port; its URL."""
    yarf = Path(sys.executable).parent / "yarf"
    command = [str(yarf), "dashboard", "--server", yarfd.address, "--listen", "127.0.0.1:0"]
    # The yarfd is plaintext loopback: no credentials of the environment apply.
    env = {k: v for k, v in os.environ.items() if k not in ("YARF_TOKEN", "YARF_TLS_CA")}
    log = tmp_path_factory.mktemp("dashboard") / "stderr.log"
    with open(log, "w") as stderr:
        process = subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=stderr, text=True, env=env
        )
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        match = re.search(r"http://127\.0\.0\.1:\d+/", line)
        assert match, f"no URL in {line!r}; stderr: {log.read_text()}"
        yield match[0]
    finally:
        process.terminate()
        process.wait(10)


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[BrowserContext]:
    # make installs Debian's chromium; without it the dashboard is untested.
    assert CHROMIUM.exists(), f"no Chromium at {CHROMIUM} (Debian package chromium)"
    with sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            str(tmp_path_factory.mktemp("chromium-profile")),
            executable_path=str(CHROMIUM),
            args=CHROMIUM_ARGS,
            headless=True,
            viewport=VIEWPORT,
        )
        yield context
        context.close()


@pytest.fixture
def page(browser: BrowserContext, dashboard: str) -> Iterator[Page]:
    """The dashboard's page; the test fails if the page logged a console error or
    raised a script error meanwhile."""
    page = browser.new_page()
    errors: list[str] = []
    page.on("console", lambda m: errors.append(f"console: {m.text}") if m.type == "error" else None)
    page.on("pageerror", lambda error: errors.append(f"page error: {error}"))
    page.goto(dashboard)
    yield page
    page.close()
    assert not errors, errors


@pytest.fixture
def endless_jobs(client: Client) -> Iterator[list[str]]:
    """Ids of jobs the test starts that would run for hours: cancelled at its end."""
    job_ids: list[str] = []
    yield job_ids
    for job_id in job_ids:
        client.cancel(job_id)
    for job_id in job_ids:
        client.wait(job_id, timeout=10)


@pytest.fixture(scope="module")
def aov_job(client: Client) -> str:
    """A finished job of the 48×32 film that asked for AOVs."""
    job_id = client.submit(film_scene(), spp=4, seed=7, name="with aovs", aovs=AOVS)
    assert client.wait(job_id, timeout=30).state == render_pb2.SUCCEEDED
    return job_id


def film_scene() -> scene_pb2.Scene:
    scene = small_scene()
    scene.film.width, scene.film.height = WIDTH, HEIGHT
    return scene


def api(url: str, body: dict[str, Any] | None = None) -> tuple[int, Any]:
    """GET (or POST ``body`` as JSON) a dashboard URL; the HTTP status and the JSON reply."""
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(url, data=data, headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(request, timeout=10) as reply:
            return reply.status, json.load(reply)
    except urllib.error.HTTPError as error:
        return error.code, json.load(error)


def fetch(url: str) -> tuple[int, dict[str, str], bytes]:
    """GET a dashboard URL; the HTTP status, the headers and the body."""
    try:
        with urllib.request.urlopen(url, timeout=30) as reply:
            return reply.status, dict(reply.headers), reply.read()
    except urllib.error.HTTPError as error:
        return error.code, dict(error.headers), error.read()


def upload(
    dashboard: str, data: bytes, query: str, headers: dict[str, str] | None = None
) -> tuple[int, Any]:
    """POST a scene file's bytes to the dashboard; the HTTP status and the JSON reply."""
    request = urllib.request.Request(
        f"{dashboard}api/jobs?{query}",
        data=data,
        headers={"Content-Type": "application/octet-stream", **(headers or {})},
    )
    try:
        with urllib.request.urlopen(request, timeout=30) as reply:
            return reply.status, json.load(reply)
    except urllib.error.HTTPError as error:
        return error.code, json.load(error)


def read_image(path: Path) -> tuple[np.ndarray, list[str]]:
    """An image file's pixels [H, W, C] as float32 (8-bit values in [0, 1]) and its
    channel names, read by OpenImageIO."""
    image = oiio.ImageInput.open(str(path))
    assert image is not None, oiio.geterror()
    try:
        spec = image.spec()
        pixels = image.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
        return np.asarray(pixels).reshape(spec.height, spec.width, spec.nchannels), list(
            spec.channelnames
        )
    finally:
        image.close()


def luminance(pixels: np.ndarray) -> np.ndarray:
    return pixels[..., :3] @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)


def api_job(dashboard: str, job_id: str) -> dict[str, Any]:
    _, reply = api(f"{dashboard}api/jobs")
    return next(job for job in reply["jobs"] if job["job_id"] == job_id)


def row(page: Page, job_id: str) -> Locator:
    return page.locator(f'tr[data-job-id="{job_id}"]')


def progress_value(page: Page, job_id: str) -> float:
    return float(row(page, job_id).locator("progress").evaluate("bar => bar.value"))


def test_the_page_lists_jobs_with_their_names_as_text(
    page: Page, client: Client, dashboard: str
) -> None:
    hostile = '<img src="x" onerror="window.injected = true">'
    job_ids = [client.submit(film_scene(), spp=2, name=name) for name in ("plain", hostile)]
    for job_id in job_ids:
        assert client.wait(job_id, timeout=30).state == render_pb2.SUCCEEDED

    for job_id, name in zip(job_ids, ("plain", hostile), strict=True):
        expect(row(page, job_id).locator(".state")).to_have_text("SUCCEEDED", timeout=WAIT_MS)
        expect(row(page, job_id).locator(".name")).to_have_text(name)
        expect(row(page, job_id).locator("[data-field=owner]")).to_have_text("local")
        expect(row(page, job_id).locator("progress")).to_have_js_property("value", 100)
    assert row(page, job_ids[1]).locator(".name img").count() == 0
    assert page.evaluate("window.injected") is None
    assert api_job(dashboard, job_ids[1])["name"] == hostile


def test_a_running_jobs_progress_rises_and_its_preview_has_the_films_size(
    page: Page, client: Client, endless_jobs: list[str]
) -> None:
    job_id = client.submit(film_scene(), spp=ENDLESS_SPP, name="rising")
    endless_jobs.append(job_id)
    expect(row(page, job_id).locator(".state")).to_have_text("RUNNING", timeout=WAIT_MS)

    page.wait_for_function(
        "id => document.querySelector(`tr[data-job-id='${id}'] progress`).value > 0",
        arg=job_id,
        timeout=WAIT_MS,
    )
    first = progress_value(page, job_id)
    page.wait_for_function(
        "([id, first]) => document.querySelector(`tr[data-job-id='${id}'] progress`).value > first",
        arg=[job_id, first],
        timeout=WAIT_MS,
    )

    preview = row(page, job_id).locator(".preview img")
    preview.wait_for(state="visible", timeout=WAIT_MS)
    page.wait_for_function(
        "id => document.querySelector(`tr[data-job-id='${id}'] .preview img`).naturalWidth > 0",
        arg=job_id,
        timeout=WAIT_MS,
    )
    size = preview.evaluate("img => [img.naturalWidth, img.naturalHeight]")
    assert size == [WIDTH, HEIGHT]


def test_cancel_turns_a_running_job_cancelled(
    page: Page, client: Client, dashboard: str, endless_jobs: list[str]
) -> None:
    job_id = client.submit(film_scene(), spp=ENDLESS_SPP, name="to cancel")
    endless_jobs.append(job_id)
    state = row(page, job_id).locator(".state")
    expect(state).to_have_text("RUNNING", timeout=WAIT_MS)

    row(page, job_id).locator("button.cancel").click()
    expect(state).to_have_text("CANCELLED", timeout=WAIT_MS)
    expect(row(page, job_id).locator("button.cancel")).to_be_disabled()
    assert api_job(dashboard, job_id)["state"] == "CANCELLED"
    assert client.status(job_id).state == render_pb2.CANCELLED


def test_changing_the_priority_of_a_queued_job_shows_the_new_value(
    page: Page, client: Client, dashboard: str, endless_jobs: list[str]
) -> None:
    endless_jobs.append(client.submit(film_scene(), spp=ENDLESS_SPP, name="first"))
    job_id = client.submit(film_scene(), spp=ENDLESS_SPP, name="second", priority=10)
    endless_jobs.append(job_id)
    expect(row(page, job_id).locator(".state")).to_have_text("QUEUED", timeout=WAIT_MS)
    expect(row(page, job_id).locator(".priority")).to_have_text("10", timeout=WAIT_MS)

    row(page, job_id).locator("input[name=priority]").fill("77")
    row(page, job_id).locator("button.set").click()
    expect(row(page, job_id).locator(".priority")).to_have_text("77", timeout=WAIT_MS)
    assert api_job(dashboard, job_id)["priority"] == 77
    assert client.status(job_id).priority == 77
    # Still 77 after the page's next refreshes.
    time.sleep(1.5)
    expect(row(page, job_id).locator(".priority")).to_have_text("77")

    # An ended job cannot be moved: the page disables the form, the API says 409.
    client.cancel(job_id)
    expect(row(page, job_id).locator("button.set")).to_be_disabled(timeout=WAIT_MS)
    status, reply = api(f"{dashboard}api/jobs/{job_id}/priority", {"priority": 60})
    assert status == 409 and reply["code"] == "FAILED_PRECONDITION", reply


def test_the_api_answers_errors_with_matching_http_statuses(dashboard: str) -> None:
    missing = f"{dashboard}api/jobs/job-999999"
    status, reply = api(f"{missing}/preview.png")
    assert status == 404 and reply["code"] == "NOT_FOUND", reply
    status, reply = api(f"{missing}/cancel", {})
    assert status == 404 and "job-999999" in reply["error"], reply
    status, reply = api(f"{missing}/priority", {"priority": 0})
    assert status == 400 and "1 to 100" in reply["error"], reply

    # Only JSON posts act: a plain form from another site cannot.
    form = urllib.request.Request(f"{missing}/cancel", data=b"x=1", method="POST")
    with pytest.raises(urllib.error.HTTPError) as caught:
        urllib.request.urlopen(form, timeout=10)
    assert caught.value.code == 415
    # Nor a script of another site (its Origin differs from the dashboard's).
    foreign = urllib.request.Request(
        f"{missing}/cancel",
        data=b"{}",
        headers={"Content-Type": "application/json", "Origin": "http://evil.example"},
    )
    with pytest.raises(urllib.error.HTTPError) as caught:
        urllib.request.urlopen(foreign, timeout=10)
    assert caught.value.code == 403

    # Only the page's own files are served.
    for path in ("../pyproject.toml", "%2e%2e/pyproject.toml", ".hidden.js", "nope.html"):
        with pytest.raises(urllib.error.HTTPError) as caught:
            urllib.request.urlopen(f"{dashboard}{path}", timeout=10)
        assert caught.value.code == 404, path


def events(log: list[str]) -> list[str]:
    return [line.split()[0].removeprefix("event=") for line in log]


def test_the_job_api_gives_a_finished_jobs_options_scene_and_log(
    dashboard: str, aov_job: str
) -> None:
    status, page = api(f"{dashboard}api/jobs/{aov_job}")
    assert status == 200, page
    assert page["job"]["job_id"] == aov_job and page["job"]["state"] == "SUCCEEDED"
    options = page["options"]
    assert (options["spp"], options["seed"], options["aovs"]) == (4, 7, AOVS)
    assert options["crop"] is None and options["threads"] >= 0
    assert page["scene"]["width"] == WIDTH and page["scene"]["height"] == HEIGHT
    assert page["scene"]["camera"] == "pinhole" and page["scene"]["shapes"] == 2
    assert events(page["log"]) == ["submitted", "started", "finished"], page["log"]
    assert all(f"job={aov_job}" in line for line in page["log"])
    assert page["error"] == "" and page["aovs"] == AOVS

    status, reply = api(f"{dashboard}api/jobs/job-999999")
    assert status == 404 and reply["code"] == "NOT_FOUND", reply


def test_downloads_are_the_exr_with_its_aov_channels_and_the_png(
    dashboard: str, aov_job: str, tmp_path: Path
) -> None:
    for extension in ("exr", "png"):
        status, headers, body = fetch(f"{dashboard}api/jobs/{aov_job}/image.{extension}")
        assert status == 200, body[:200]
        disposition = headers["Content-Disposition"]
        assert disposition == f'attachment; filename="{aov_job}.{extension}"'
        (tmp_path / f"image.{extension}").write_bytes(body)

    exr, channels = read_image(tmp_path / "image.exr")
    assert exr.shape[:2] == (HEIGHT, WIDTH)
    assert channels[:3] == ["R", "G", "B"]
    assert {f"{name}.{c}" for name in AOVS for c in "RGB"} <= set(channels), channels
    albedo = exr[..., channels.index("albedo.R")]
    assert np.allclose(albedo[albedo > 0], 0.5, atol=0.01)  # the grey material's

    png, _ = read_image(tmp_path / "image.png")
    assert png.shape[:2] == (HEIGHT, WIDTH) and png.std() > 0


def test_an_aov_is_a_png_of_the_film_mapped_for_display(
    dashboard: str, aov_job: str, tmp_path: Path
) -> None:
    shown = {}
    for name in AOVS:
        status, headers, body = fetch(f"{dashboard}api/jobs/{aov_job}/aov/{name}.png")
        assert status == 200 and headers["Content-Type"] == "image/png", body[:200]
        (tmp_path / f"{name}.png").write_bytes(body)
        shown[name] = read_image(tmp_path / f"{name}.png")[0]
        assert shown[name].shape[:2] == (HEIGHT, WIDTH), name
    # Depth stretched over its range: nearest 0, farthest 1.
    assert shown["depth"].min() == 0 and shown["depth"].max() == 1
    # Normals from [-1, 1]: the sphere's, facing the camera, are bluish (z > 0).
    assert shown["sh_normal"][..., 2].mean() > 0.5

    for name, why in (("uv", "did not ask"), ("nope", "known:")):
        status, reply = api(f"{dashboard}api/jobs/{aov_job}/aov/{name}.png")
        assert status == 404 and why in reply["error"], reply


def test_an_uploaded_mitsuba_scene_is_submitted_with_its_options(
    dashboard: str, client: Client
) -> None:
    status, job = upload(dashboard, MITSUBA_SCENE, "file=ball.xml&transport=path&name=uploaded")
    assert status == 201, job
    assert job["name"] == "uploaded" and job["samples_total"] == 4  # the file's sample count
    assert client.wait(job["job_id"], timeout=30).state == render_pb2.SUCCEEDED
    details = client.details(job["job_id"])
    assert (details.scene.width, details.scene.height) == (32, 24)
    assert details.options.transport.class_name == "path"

    status, job = upload(dashboard, MITSUBA_SCENE, "file=dir%2Fball.xml&spp=2&aov=albedo")
    assert status == 201, job
    assert job["name"] == "ball.xml" and job["samples_total"] == 2
    assert client.wait(job["job_id"], timeout=30).state == render_pb2.SUCCEEDED


def test_uploads_are_refused_with_their_reasons(dashboard: str) -> None:
    refusals = [
        (MITSUBA_SCENE, "spp=2", 400, "name the scene file"),
        (MITSUBA_SCENE, "file=ball.obj", 400, "one of .xml, .pbrt"),
        (MITSUBA_SCENE[:200], "file=broken.xml", 400, "broken.xml:"),
        (MITSUBA_SCENE, "file=ball.xml&spp=0", 400, "spp: must be 1 to"),
        (MITSUBA_SCENE, "file=ball.xml&aov=albedoo", 400, "did you mean 'albedo'"),
        (MITSUBA_SCENE, "file=ball.xml&colour=red", 400, "unrecognized arguments"),
        (MITSUBA_SCENE, "file=ball.xml&time_limit=5", 400, "no time limit"),
        (b"", "file=empty.json", 400, "empty"),
        (b'{"shapes": [{"mesh": {"file": "../../etc/passwd"}}]}', "file=m.json", 400, "inline"),
        (b'Include "/etc/passwd"\n', "file=inc.pbrt", 400, "not found inside the scene's"),
        (
            b'<scene version="3.0.0"><include filename="/etc/passwd"/></scene>',
            "file=i.xml",
            400,
            "not found inside the scene's",
        ),
        (b"x" * (MAX_UPLOAD_BYTES + 1), "file=big.xml", 413, "at most 16 MiB"),
    ]
    for data, query, expected, message in refusals:
        status, reply = upload(dashboard, data, query)
        assert status == expected and message in reply["error"], (query, reply)
    # A file of this machine outside the upload is never read, and whether it
    # exists cannot be told from the answer.
    answers = [
        upload(dashboard, f'Include "{name}"\n'.encode(), "file=inc.pbrt")[1]["error"]
        for name in ("/etc/passwd", "/etc/no_such_file_here")
    ]
    assert answers[0].replace("passwd", "X") == answers[1].replace("no_such_file_here", "X")
    # The importer's own message about the broken file, without the server's folders.
    status, reply = upload(dashboard, MITSUBA_SCENE[:200], "file=broken.xml")
    assert "malformed XML" in reply["error"] and "/tmp" not in reply["error"], reply

    # Another site's script cannot upload, nor can its plain form.
    origin = {"Origin": "http://evil.example"}
    status, reply = upload(dashboard, MITSUBA_SCENE, "file=ball.xml", origin)
    assert status == 403, reply
    status, reply = upload(dashboard, b"x=1", "file=ball.xml", {"Content-Type": "text/plain"})
    assert status == 415, reply


def box_inside(box: dict[str, float] | None, width: float) -> bool:
    return (
        box is not None and box["width"] > 0 and 0 <= box["x"] and box["x"] + box["width"] <= width
    )


def overlap(a: dict[str, float], b: dict[str, float]) -> float:
    """The area two bounding boxes share."""
    dx = min(a["x"] + a["width"], b["x"] + b["width"]) - max(a["x"], b["x"])
    dy = min(a["y"] + a["height"], b["y"] + b["height"]) - max(a["y"], b["y"])
    return max(dx, 0.0) * max(dy, 0.0)


def crop(shot: np.ndarray, box: dict[str, float]) -> np.ndarray:
    """The screenshot's pixels inside an element's bounding box (the viewport's scale is 1)."""
    x0, y0 = math.ceil(box["x"]), math.ceil(box["y"])
    x1, y1 = math.floor(box["x"] + box["width"]), math.floor(box["y"] + box["height"])
    return shot[y0:y1, x0:x1]


def check_contrast(shot: np.ndarray, page: Page) -> None:
    """The heading's text stands out of the page's background."""
    heading = luminance(crop(shot, page.locator("h1").bounding_box()))
    assert heading.max() - heading.min() > 0.5


def test_the_job_page_shows_the_image_parameters_aovs_and_log_of_a_finished_job(
    page: Page, dashboard: str, aov_job: str, tmp_path: Path
) -> None:
    link = row(page, aov_job).locator(".job-id a")
    expect(row(page, aov_job).locator(".state")).to_have_text("SUCCEEDED", timeout=WAIT_MS)
    preview = row(page, aov_job).locator(".preview img")
    page.wait_for_function(
        "img => img.complete && img.naturalWidth > 0", arg=preview.element_handle()
    )
    page.screenshot(path=tmp_path / "queue.png")
    shot, _ = read_image(tmp_path / "queue.png")
    assert shot.shape[:2] == (VIEWPORT["height"], VIEWPORT["width"])
    check_contrast(shot, page)
    thumbnail = luminance(crop(shot, preview.bounding_box()))
    assert thumbnail.mean() > 0.1 and thumbnail.std() > 0.05  # the lit scene, not blank

    link.click()
    assert page.url.endswith(f"#/jobs/{aov_job}")
    expect(page.locator("#queue-view")).to_be_hidden()
    expect(page.locator("#job-title")).to_have_text("with aovs")
    expect(page.locator("#job-status")).to_contain_text("SUCCEEDED")
    expect(page.locator("#job-scene")).to_contain_text(f"{WIDTH} × {HEIGHT}")
    options = page.locator("#job-options")
    expect(options).to_contain_text("Samples per pixel4")
    expect(options).to_contain_text("albedo, sh_normal, depth")
    log = page.locator("#job-log li")
    expect(log).to_have_count(3)
    assert events(log.all_text_contents()) == ["submitted", "started", "finished"]
    expect(page.locator("#job-error-section")).to_be_hidden()
    for download, extension in (("#download-exr", "exr"), ("#download-png", "png")):
        expect(page.locator(download)).to_have_attribute(
            "href", f"/api/jobs/{aov_job}/image.{extension}"
        )
    image = page.locator("#job-image")
    aovs = page.locator("#job-aovs img")
    expect(aovs).to_have_count(len(AOVS))
    for element in [image, *aovs.all()]:
        page.wait_for_function(
            "img => img.complete && img.naturalWidth > 0", arg=element.element_handle()
        )

    # Laid out: everything within the viewport's width, the image beside the
    # tables without covering them, at the film's aspect ratio.
    width = VIEWPORT["width"]
    laid_out = ["#job-title", "#job-image", "#job-downloads", "#job-status", "#job-options"]
    for selector in [*laid_out, "#job-scene", "#job-log"]:
        assert box_inside(page.locator(selector).bounding_box(), width), selector
    for figure in page.locator("#job-aovs figure").all():
        assert box_inside(figure.bounding_box(), width)
    image_box = image.bounding_box()
    assert image_box is not None
    for table in ("#job-status", "#job-options", "#job-scene"):
        assert overlap(image_box, page.locator(table).bounding_box()) == 0, table
    assert image_box["width"] / image_box["height"] == pytest.approx(WIDTH / HEIGHT, rel=0.02)
    assert image_box["width"] >= 4 * WIDTH  # enlarged, pixelated

    page.screenshot(path=tmp_path / "job.png", full_page=True)
    shot, _ = read_image(tmp_path / "job.png")
    assert shot.shape[1] == VIEWPORT["width"] and shot.shape[0] >= VIEWPORT["height"]
    check_contrast(shot, page)
    # The image as the page shows it is the job's PNG, pixel for pixel: sample
    # the screenshot at the middle of each enlarged pixel.
    _, _, body = fetch(f"{dashboard}api/jobs/{aov_job}/image.png")
    (tmp_path / "image.png").write_bytes(body)
    expected, _ = read_image(tmp_path / "image.png")
    shown = crop(shot, image_box)
    rows = ((np.arange(HEIGHT) + 0.5) * shown.shape[0] / HEIGHT).astype(int)
    columns = ((np.arange(WIDTH) + 0.5) * shown.shape[1] / WIDTH).astype(int)
    sampled = shown[rows][:, columns, :3]
    assert np.abs(sampled - expected[..., :3]).max() <= 3 / 255
    # The AOVs as mapped for display: the grey material's albedo (sRGB 0.735)
    # everywhere; normals and depth that vary over the sphere.
    thumbnails = {
        name: crop(shot, page.locator(f'#job-aovs [data-aov="{name}"] img').bounding_box())
        for name in AOVS
    }
    assert np.abs(thumbnails["albedo"][..., :3] - 0.735).max() < 0.02
    for name in ("sh_normal", "depth"):
        assert luminance(thumbnails[name]).std() > 0.05, name


def test_a_scene_uploaded_with_the_form_is_queued_and_opens_its_page(
    page: Page, client: Client
) -> None:
    form = page.locator("#upload")
    form.locator("input[type=file]").set_input_files(
        files=[{"name": "ball.xml", "mimeType": "text/xml", "buffer": MITSUBA_SCENE}]
    )
    form.locator("input[name=spp]").fill("2")
    form.locator("select[name=transport]").select_option("path")
    form.locator("button[type=submit]").click()
    status = page.locator("#upload-status a")
    expect(status).to_have_text(re.compile(r"Submitted job-\d+"), timeout=WAIT_MS)
    job_id = re.search(r"job-\d+", status.text_content() or "")[0]
    expect(page.locator("#upload-error")).to_be_hidden()
    expect(row(page, job_id).locator(".name")).to_have_text("ball.xml", timeout=WAIT_MS)
    expect(row(page, job_id).locator(".state")).to_have_text("SUCCEEDED", timeout=WAIT_MS)
    assert client.details(job_id).options.spp == 2

    status.click()
    expect(page.locator("#job-scene")).to_contain_text("32 × 24", timeout=WAIT_MS)
    expect(page.locator("#job-options")).to_contain_text("Transportpath")
    expect(page.locator("#job-aov-section")).to_be_hidden()
    page.go_back()
    expect(page.locator("#queue-view")).to_be_visible()
    expect(row(page, job_id)).to_be_visible()


@pytest.fixture(scope="module")
def secured_yarfd(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[LocalServer, Path]]:
    """A yarfd with TLS and tokens (alice and bob submit), alice's client by default;
    and its certificate."""
    folder = tmp_path_factory.mktemp("secured")
    cert, key, tokens = folder / "cert.pem", folder / "key.pem", folder / "tokens"
    subprocess.run(
        [
            "openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1",
            "-subj", "/CN=localhost", "-addext", "subjectAltName=DNS:localhost,IP:127.0.0.1",
            "-keyout", str(key), "-out", str(cert),
        ],
        check=True,
        capture_output=True,
    )  # fmt: skip
    tokens.write_text(f"{ALICE} alice submit\n{BOB} bob submit\n")
    args = ["--tls-cert", str(cert), "--tls-key", str(key), "--tokens", str(tokens)]
    with LocalServer(extra_args=args, tls_ca=cert, token=ALICE) as server:
        yield server, cert


def test_the_api_answers_403_for_another_users_job(
    secured_yarfd: tuple[LocalServer, Path],
) -> None:
    server, cert = secured_yarfd
    with server.client() as alice:
        job_id = alice.submit(film_scene(), spp=1, name="alice's")
        assert alice.wait(job_id, timeout=30).state == render_pb2.SUCCEEDED

    # A dashboard of bob's, in this process.
    with (
        Client(server.address, token=BOB, tls_ca=cert) as bob,
        DashboardServer(("127.0.0.1", 0), bob, find_web_dir()) as web,
    ):
        threading.Thread(target=web.serve_forever, daemon=True).start()
        try:
            for path, body in ((f"{job_id}/cancel", {}), (f"{job_id}/priority", {"priority": 9})):
                status, reply = api(f"{web.url}api/jobs/{path}", body)
                assert status == 403 and reply["code"] == "PERMISSION_DENIED", (path, reply)
            status, reply = api(f"{web.url}api/jobs/{job_id}/preview.png")
            assert status == 403, reply
            status, reply = api(f"{web.url}api/jobs")
            assert status == 200 and job_id not in {job["job_id"] for job in reply["jobs"]}
        finally:
            web.shutdown()


def test_dashboard_without_its_page_files_says_where_it_looked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["dashboard", "--web-dir", str(tmp_path), "--server", "127.0.0.1:1"])
    assert code == 2
    assert str(tmp_path) in capsys.readouterr().err
