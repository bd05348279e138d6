"""What one reproduction run measured: records, checks, and the run as a whole."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .paper import PAPER_METRICS, VARIANTS, PaperCell, paper_tables

__all__ = ["Beside", "Check", "Record", "Reproduction"]


# -- results -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Record:
    """One measured error: a table row (surface, h, function, method) at one n.

    ``l2`` and ``linf`` are normalized (by ‖Δf‖₂ and max|Δf|), ``abs_linf`` is max|Lf − Δf|
    (the metric of the paper's Table 3); ``floor_*`` are the errors of the continuous L_h
    (BSW only) and ``disc_l2`` = ‖Lf − L_h f‖₂/‖Δf‖₂.
    """

    table: str
    h: float
    function: str
    method: str
    n: int
    l2: float
    linf: float
    scored: int
    floor_l2: float = math.nan
    floor_linf: float = math.nan
    disc_l2: float = math.nan
    abs_linf: float = math.nan
    floor_abs_linf: float = math.nan


@dataclass(frozen=True)
class Check:
    """A claim of the paper (or of issue 3) tested on the measured numbers."""

    claim: str
    holds: bool
    detail: str


@dataclass
class Reproduction:
    """All measured errors, the claims checked on them, the markdown and the files written.

    ``records`` follow our protocol; ``variants`` are the extra rows that measure a choice
    the paper leaves open (tables "plane-all", "plane-stratified", "noisy-strong", see
    :data:`VARIANTS`); ``beside`` puts each published cell beside ours (protocol and variants).
    """

    records: list[Record]
    ns: tuple[int, ...]
    variants: list[Record] = field(default_factory=list)
    beside: list[Beside] = field(default_factory=list)
    checks: list[Check] = field(default_factory=list)
    markdown: str = ""
    files: list[Path] = field(default_factory=list)
    seconds: float = 0.0

    def select(self, **where: object) -> list[Record]:
        """Records whose fields equal the given values, in order of n."""
        out = [r for r in self.records if all(getattr(r, k) == v for k, v in where.items())]
        return sorted(out, key=lambda r: r.n)

    def errors(self, table: str, function: str, method: str, norm: str = "l2",
               h: float | None = None) -> np.ndarray:
        """The errors of one table row as an array over ``ns``."""
        where: dict[str, object] = {"table": table, "function": function, "method": method}
        if h is not None:
            where["h"] = h
        return np.array([getattr(r, norm) for r in self.select(**where)])

    @property
    def ok(self) -> bool:
        return all(c.holds for c in self.checks)


@dataclass(frozen=True)
class Beside:
    """One published cell beside our error for it, in the paper's metric.

    ``table`` and ``h`` locate our row; ``variant`` is "" for our protocol, else the other
    choice (a value of :data:`VARIANTS`) under which ``ours`` was measured.
    """

    paper: PaperCell
    ours: float
    table: str
    h: float
    variant: str = ""

    @property
    def ratio(self) -> float:
        """ours / paper: below 1 where our error is smaller."""
        return self.ours / self.paper.error


def _beside(records: Sequence[Record]) -> list[Beside]:
    index = {(r.table, r.h, r.function, r.method, r.n): r for r in records}
    out = []
    for cell in paper_tables():
        ours_table, metric = PAPER_METRICS[cell.table]
        for table, variant in ((ours_table, ""), *VARIANTS[cell.table]):
            # the paper's COT rows have no h: ours are shown for each h we tabulate
            hs = sorted({r.h for r in records if r.table == table})
            for h in hs if cell.h is None else [h for h in hs if math.isclose(h, cell.h)]:
                r = index.get((table, h, cell.function, cell.method, cell.n))
                if r is not None:
                    out.append(Beside(cell, float(getattr(r, metric)), table, h, variant))
    return out
