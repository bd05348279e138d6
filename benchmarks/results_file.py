"""Writes a benchmark's results into benchmarks/RESULTS.md, leaving the other benchmarks' alone.

RESULTS.md holds one section per benchmark script, ``## bench_x.py``; a script that measures
several things writes each as a ``### title`` subsection of its own section. A run replaces
what the same script wrote under the same title before: the file holds current figures only
(their history is in git and CHANGELOG.md).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "RESULTS.md"


def _replace(text: str, level: str, title: str, body: str) -> str:
    """``text`` with its ``level title`` block (up to the next heading of that level or above) set to body."""
    stop = "|".join(re.escape("#" * i + " ") for i in range(1, len(level) + 1))
    pattern = re.compile(rf"^{re.escape(level)} {re.escape(title)}\n.*?(?=^(?:{stop})|\Z)", re.S | re.M)
    if pattern.search(text):
        return pattern.sub(lambda _: body + "\n", text, count=1).rstrip() + "\n"
    return text.rstrip() + "\n\n" + body


def write_section(title: str, lines: list[str], script: str | None = None) -> None:
    """Set the subsection ``### title`` of the section ``## script`` of RESULTS.md to ``lines``.

    ``script`` defaults to the running script's file name; when ``title`` is the script's
    name the lines are the section itself.
    """
    script = script or Path(sys.argv[0]).name
    body = "\n".join(lines).rstrip() + "\n"
    text = RESULTS.read_text() if RESULTS.exists() else "# Benchmark results\n"
    if title == script:
        text = _replace(text, "##", script, f"## {script}\n\n{body}")
    else:
        match = re.search(rf"^## {re.escape(script)}\n.*?(?=^## |\Z)", text, re.S | re.M)
        section = match.group(0) if match else f"## {script}\n"
        section = _replace(section, "###", title, f"### {title}\n\n{body}")
        section = section.rstrip() + "\n\n"
        text = text.replace(match.group(0), section) if match else text.rstrip() + "\n\n" + section
    RESULTS.write_text(text.rstrip() + "\n")


def publish(lines: list[str], no_write: bool) -> None:
    """The running script's section of RESULTS.md set to ``lines``, or printed with ``no_write``."""
    if no_write:
        print("\n".join(lines))
    else:
        write_section(Path(sys.argv[0]).name, lines)


if __name__ == "__main__":  # a module the scripts import: run, it only answers --help
    import argparse

    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
