"""The web dashboard (`yarf dashboard`) in headless Chromium, against a real yarfd.

The yarfd runs one job at a time (--max-running-jobs 1), so that a second
job stays queued while the first renders.
"""

from __future__ import annotations

import json
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

import pytest
from conftest import small_scene
from playwright.sync_api import BrowserContext, Locator, Page, expect, sync_playwright

from yarf import Client, LocalServer
from yarf.cli import main
from yarf.dashboard import DashboardServer, find_web_dir
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
        )
        yield context
        context.close()


@pytest.fixture
def page(browser: BrowserContext, dashboard: str) -> Iterator[Page]:
    page = browser.new_page()
    page.goto(dashboard)
    yield page
    page.close()


@pytest.fixture
def endless_jobs(client: Client) -> Iterator[list[str]]:
    """Ids of jobs the test starts that would run for hours: cancelled at its end."""
    job_ids: list[str] = []
    yield job_ids
    for job_id in job_ids:
        client.cancel(job_id)
    for job_id in job_ids:
        client.wait(job_id, timeout=10)


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
