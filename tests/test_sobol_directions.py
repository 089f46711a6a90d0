"""The Sobol direction numbers compiled into sobol_nd are Joe & Kuo's as scipy ships
them: components/cpp/samplers/sobol_directions.h is what tools/sobol_directions.py
writes from scipy's copy of new-joe-kuo-6.21201."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_compiled_table_is_the_one_written_from_scipys_copy() -> None:
    spec = importlib.util.spec_from_file_location(
        "sobol_directions", ROOT / "tools" / "sobol_directions.py"
    )
    assert spec is not None and spec.loader is not None
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    assert tool.OUT.read_text() == tool.header_text()
