"""Where the Cornell box path tracer's time goes, with Mitsuba 3's for comparison.

Samples yarfd with `perf record` while it renders the Cornell box, and a
Mitsuba 3 `llvm_ad_rgb` render of the same scene the same way, then writes
the top functions and libraries by share of samples, and the hardware
counters (IPC, cache misses) where the machine exposes them (a virtual
machine often does not; the report says so). Mitsuba's kernel is code its
JIT made at run time, which perf can only name as anonymous addresses; its
share is reported as "JIT code".

Written to out/bench/profile.txt (the CPU model first);
bench/profiles/ keeps committed copies. ``--yarfd PATH`` profiles another
build's yarfd (an older commit's, for a before-and-after pair), with the
commit of the tree that binary was built in.
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_report import cpu_model
from cornell_box import LLVM, MITSUBA_SCENE, SCENE

from yarf.client import Client
from yarf.scene import load_scene
from yarf.server import LocalServer

ROOT = Path(__file__).resolve().parent.parent
SPP = int(os.environ.get("YARF_PROFILE_SPP", "128"))
TOP = 25
COUNTERS = "cycles,instructions,cache-references,cache-misses"


def report(data: Path, sort: str) -> list[str]:
    """perf's table of the top entries by share of samples, lines with a %."""
    result = subprocess.run(
        [
            "perf",
            "report",
            "-i",
            str(data),
            "--no-children",
            "--sort",
            sort,
            "--stdio",
            "-g",
            "none",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    rows = [line.rstrip() for line in result.stdout.splitlines() if re.match(r"\s+\d+\.\d+%", line)]
    # perf pads each row with empty columns ("-  -") and runs of spaces.
    return [re.sub(r"\s{2,}", "  ", re.sub(r"(\s+-)+\s*$", "", row.strip())) for row in rows[:TOP]]


def counters(stat_output: str) -> list[str]:
    """IPC and cache-miss lines of perf stat, or why there are none."""
    values: dict[str, float] = {}
    for line in stat_output.splitlines():
        match = re.match(r"\s*([\d,.]+)\s+([\w-]+)", line)
        if match:
            values[match.group(2)] = float(match.group(1).replace(",", ""))
    if "cycles" not in values or "instructions" not in values:
        return ["hardware counters: not supported on this machine (perf stat: <not supported>)"]
    lines = [f"IPC: {values['instructions'] / values['cycles']:.2f}"]
    if values.get("cache-references"):
        share = values.get("cache-misses", 0) / values["cache-references"]
        lines.append(f"cache misses: {share:.1%} of {values['cache-references']:.3g} references")
    return lines


def profile_yarf(folder: Path, yarfd: Path | None) -> list[str]:
    data = folder / "yarf.data"
    with LocalServer(binary=yarfd) as server:
        client = Client(server.address)
        scene = load_scene(SCENE)
        client.wait(client.submit(scene, spp=4, seed=1))  # plugins loaded, scene built
        pid = str(server.pid)
        record = subprocess.Popen(
            ["perf", "record", "-F", "999", "-o", str(data), "-p", pid], stderr=subprocess.DEVNULL
        )
        stat = subprocess.Popen(
            ["perf", "stat", "-e", COUNTERS, "-p", pid], stderr=subprocess.PIPE, text=True
        )
        time.sleep(0.5)
        status = client.wait(client.submit(scene, spp=SPP, seed=1))
        for process in (record, stat):
            process.send_signal(signal.SIGINT)
        _, stat_output = stat.communicate()
        record.wait()
    pixels = 256 * 256
    lines = [
        f"## yarf path tracer, Cornell box {SPP} spp: "
        f"{pixels * SPP / status.elapsed_seconds / 1e6:.2f} M samples/s",
        *counters(stat_output),
        "",
        "by library:",
        *report(data, "dso"),
        "",
        "by function:",
        *report(data, "dso,symbol"),
    ]
    return lines


def profile_mitsuba(folder: Path) -> list[str]:
    data = folder / "mitsuba.data"
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=str(LLVM))
    command = [
        sys.executable,
        str(ROOT / "bench" / "mitsuba_render.py"),
        str(MITSUBA_SCENE),
        "--variant",
        "llvm_ad_rgb",
        "--spp",
        str(SPP),
    ]
    stat = subprocess.run(
        ["perf", "stat", "-e", COUNTERS, "--", *command],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    subprocess.run(
        ["perf", "record", "-F", "999", "-o", str(data), "--", *command],
        env=env,
        capture_output=True,
        check=True,
    )
    by_library = [row.replace("[unknown]", "[unknown] (JIT code)") for row in report(data, "dso")]
    return [
        f"## Mitsuba 3 llvm_ad_rgb, Cornell box {SPP} spp (whole process: import, JIT, render)",
        f"render: {stat.stdout.strip().splitlines()[-1]}",
        *counters(stat.stderr),
        "",
        "by library:",
        *by_library,
        "",
        "by function:",
        *report(data, "dso,symbol"),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--yarfd", type=Path, help="the yarfd to profile (default: this build's)")
    args = parser.parse_args()
    tree = args.yarfd.resolve().parent if args.yarfd else ROOT
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"],
        cwd=tree,
        capture_output=True,
        text=True,
        check=False,
    ).stdout.strip()
    with tempfile.TemporaryDirectory() as folder:
        lines = [
            f"# Cornell box profile — CPU: {cpu_model()}, {os.cpu_count()} threads, "
            f"commit {commit}",
            "",
            *profile_yarf(Path(folder), args.yarfd),
            "",
            *profile_mitsuba(Path(folder)),
        ]
    text = "\n".join(lines) + "\n"
    out = ROOT / "out" / "bench" / "profile.txt"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    print(text)
    print(f"written {out}")


if __name__ == "__main__":
    main()
