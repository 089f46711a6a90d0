"""The code in docs/ runs: every ```bash and ```python block of each page,
in order, in a fresh folder holding the repository's scenes, with the
virtual environment's and the build's programs on PATH. A page's Python
blocks share one namespace; a failing block fails its page's test with
the block and its output."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = sorted((ROOT / "docs").glob("*.md"))
BLOCK = re.compile(r"^```(bash|python)\n(.*?)^```", re.M | re.S)

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


def test_there_are_pages_with_code() -> None:
    assert {p.name for p in PAGES} >= {
        "getting-started.md",
        "python.md",
        "components.md",
        "scenes.md",
    }
    assert all(blocks(p) for p in PAGES)


@pytest.mark.parametrize("page", PAGES, ids=[p.stem for p in PAGES])
def test_every_block_of_the_page_runs(page: Path, tmp_path: Path) -> None:
    import json

    (tmp_path / "scenes").symlink_to(ROOT / "scenes")
    (tmp_path / "components").symlink_to(ROOT / "components")
    (tmp_path / "build").symlink_to(ROOT / "build")
    (tmp_path / "tests").symlink_to(ROOT / "tests")
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join(
        [str(Path(sys.executable).parent), str(ROOT / "build" / "bin"), env.get("PATH", "")]
    )
    done = subprocess.run(
        [sys.executable, "-c", DRIVER],
        input=json.dumps(blocks(page)),
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, f"{page.name}:\n{done.stdout[-4000:]}\n{done.stderr[-4000:]}"
