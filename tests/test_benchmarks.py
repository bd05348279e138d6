"""The scripts of benchmarks/ parse their options: ``--help`` prints them, it does not run the
benchmark (several had none, and ``--help`` ran them, some writing RESULTS.md)."""

from __future__ import annotations

import ast
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def test_every_script_parses_its_options() -> None:
    missing = []
    for path in sorted(BENCHMARKS.glob("*.py")):
        text = path.read_text(encoding="utf-8")
        runs = any(isinstance(node, ast.If) and "__main__" in ast.unparse(node.test)
                   for node in ast.parse(text).body)
        if runs and "ArgumentParser" not in text:
            missing.append(path.name)
    assert not missing, f"scripts without an argument parser: {missing}"
