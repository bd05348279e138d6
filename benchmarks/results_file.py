"""Writes one section of benchmarks/RESULTS.md, leaving the other benchmarks' sections alone."""

from __future__ import annotations

import re
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "RESULTS.md"


def write_section(title: str, lines: list[str]) -> None:
    """Replace (or append) the section ``## title`` of RESULTS.md with ``lines``."""
    section = f"## {title}\n\n" + "\n".join(lines).rstrip() + "\n"
    if not RESULTS.exists():
        RESULTS.write_text("# Benchmark results\n\n" + section)
        return
    text = RESULTS.read_text()
    pattern = re.compile(rf"^## {re.escape(title)}\n.*?(?=^## |\Z)", re.S | re.M)
    if pattern.search(text):
        text = pattern.sub(lambda _: section + "\n", text, count=1).rstrip() + "\n"
    else:
        text = text.rstrip() + "\n\n" + section
    RESULTS.write_text(text)
