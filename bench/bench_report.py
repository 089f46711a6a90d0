"""What a benchmark reports besides its figures: the machine, and where its results go."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def cpu_model() -> str:
    """The CPU's model name from /proc/cpuinfo; speed ratios differ between CPUs."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


def print_log_tail(lines: list[str]) -> None:
    """The end of yarfd's log, indented under the figures."""
    print("  yarfd log (tail):")
    for line in lines:
        print(f"    {line}")


def write_result(name: str, report: dict[str, object]) -> None:
    """``report`` as out/bench/NAME.json and as one machine-readable ``RESULT`` line."""
    output = ROOT / "out" / "bench"
    output.mkdir(parents=True, exist_ok=True)
    (output / f"{name}.json").write_text(json.dumps(report, indent=2))
    print("RESULT " + json.dumps(report))
