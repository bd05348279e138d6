"""Opt-in progress reporting: a text bar on stderr, or a callback of the user's."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable

__all__ = ["ProgressLike", "make_progress", "onward"]

#: ``None``/``False`` (silent), ``True`` (a bar on stderr) or ``callback(fraction, stage)``.
ProgressLike = bool | Callable[[float, str], None] | None


class _Bar:
    def __init__(self, stream=None):
        self.stream = stream or sys.stderr
        self.t0 = time.perf_counter()
        self.last = -1

    def __call__(self, fraction: float, stage: str) -> None:
        pct = int(100 * fraction)
        if pct == self.last and fraction < 1:
            return
        self.last = pct
        filled = pct // 4
        elapsed = time.perf_counter() - self.t0
        bar = "#" * filled + "-" * (25 - filled)
        end = "\n" if fraction >= 1 and stage == "done" else ""
        self.stream.write(f"\r{stage:>10s} [{bar}] {pct:3d}%  {elapsed:6.1f}s{end}")
        self.stream.flush()


def make_progress(progress: ProgressLike) -> Callable[[float, str], None] | None:
    """Turn the user's ``progress`` argument into a ``callback(fraction, stage)`` or None."""
    if progress is None or progress is False:
        return None
    if progress is True:
        return _Bar()
    if callable(progress):
        return progress
    raise TypeError(f"progress must be None, a bool or a callable(fraction, stage); got {progress!r}")


def onward(report: Callable[[float, str], None] | None) -> Callable[[float, str], None] | None:
    """``report`` for work that may start a stage over (a solver's retry): a fraction below the
    last one begins the stage again in what is left of the bar, so the bar never goes back.

    Examples
    --------
    >>> seen = []
    >>> r = onward(lambda f, s: seen.append(round(f, 2)))
    >>> for f in (0.0, 0.8, 0.0, 0.5, 1.0):
    ...     r(f, "stage")
    >>> seen
    [0.0, 0.8, 0.8, 0.9, 1.0]
    """
    if report is None:
        return None
    base, span, last, shown = 0.0, 1.0, 0.0, 0.0

    def call(fraction: float, stage: str) -> None:
        nonlocal base, span, last, shown
        if fraction < last:
            base, span = shown, 1.0 - shown
        last = fraction
        shown = max(shown, base + span * fraction)
        report(shown, stage)
    return call
