"""The code in docs/ runs: every ```bash and ```python block of each page,
in order, in a fresh folder holding the repository's scenes, with the
virtual environment's and the build's programs on PATH. A page's Python
blocks share one namespace; a failing block fails its page's test with
the block and its output. A page runs in a process group of its own:
whatever it left running in the background (a page that failed before
its last block stops the servers it started) is stopped at its end."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
# The generated plugin reference holds no code: test_parameter_schemas.py checks it.
PAGES = sorted(p for p in (ROOT / "docs").glob("*.md") if p.name != "plugins.md")
BLOCK = re.compile(r"^```(bash|python)\n(.*?)^```", re.M | re.S)
# How long what a page left running has to stop after SIGTERM.
STOP_SECONDS = 10.0
# A page's time, under pytest's own timeout so that a page that hangs
# reports the block it hung in and what it printed.
PAGE_SECONDS = 480.0

# Runs a page's blocks, given as (language, code) pairs on stdin.
DRIVER = """
import json, subprocess, sys
namespace = {"__name__": "__doc__"}
for number, (language, code) in enumerate(json.load(sys.stdin), 1):
    print(f"--- block {number} ({language})", flush=True)
    if language == "python":
        exec(compile(code, f"block {number}", "exec"), namespace)
    else:
        subprocess.run(["bash", "-euo", "pipefail", "-c", code], check=True)
    sys.stdout.flush()
"""


def blocks(page: Path) -> list[tuple[str, str]]:
    return [(m.group(1), m.group(2)) for m in BLOCK.finditer(page.read_text())]


def stop_group(group: int) -> None:
    """SIGTERM to the process group, then SIGKILL to what is left of it."""
    for number in (signal.SIGTERM, signal.SIGKILL):
        try:
            os.killpg(group, number)
        except ProcessLookupError:
            return
        deadline = time.monotonic() + STOP_SECONDS
        while time.monotonic() < deadline:
            try:
                os.killpg(group, 0)
            except ProcessLookupError:
                return
            time.sleep(0.1)


def test_there_are_pages_with_code() -> None:
    assert {p.name for p in PAGES} >= {
        "getting-started.md",
        "python.md",
        "components.md",
        "scenes.md",
        "farm.md",
    }
    assert all(blocks(p) for p in PAGES)


@pytest.mark.parametrize("page", PAGES, ids=[p.stem for p in PAGES])
def test_every_block_of_the_page_runs(page: Path, tmp_path: Path) -> None:
    import json

    (tmp_path / "scenes").symlink_to(ROOT / "scenes")
    (tmp_path / "components").symlink_to(ROOT / "components")
    (tmp_path / "build").symlink_to(ROOT / "build")
    (tmp_path / "tests").symlink_to(ROOT / "tests")
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join(
        [str(Path(sys.executable).parent), str(ROOT / "build" / "bin"), env.get("PATH", "")]
    )
    # Files, not pipes: a process a page leaves running keeps no pipe open.
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        driver = subprocess.Popen(
            [sys.executable, "-c", DRIVER],
            stdin=subprocess.PIPE,
            stdout=out,
            stderr=err,
            cwd=tmp_path,
            env=env,
            text=True,
            start_new_session=True,
        )
        timed_out = False
        try:
            driver.communicate(json.dumps(blocks(page)), timeout=PAGE_SECONDS)
        except subprocess.TimeoutExpired:
            timed_out = True
        finally:
            if driver.poll() is None:
                driver.kill()
            driver.wait()
            # The group outlives its leader while any of its processes runs.
            stop_group(driver.pid)
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    verdict = f"ran over {PAGE_SECONDS:.0f} s" if timed_out else f"exit {driver.returncode}"
    assert not timed_out and driver.returncode == 0, (
        f"{page.name} ({verdict}):\n{stdout[-4000:]}\n{stderr[-4000:]}"
    )
