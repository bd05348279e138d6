"""The paper's published numbers (Tables 1-4 of Belkin, Sun and Wang, SoCG 2008)."""

from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib import resources

from .settings import STRONG_NOISE

__all__ = ["PAPER_METRICS", "PaperCell", "VARIANTS", "paper_tables"]


# -- the paper's published numbers ---------------------------------------------------------
@dataclass(frozen=True)
class PaperCell:
    """One published cell of Tables 1–4 of Belkin, Sun and Wang (SoCG 2008, Section 5).

    ``metric`` is "L2" (normalized, ‖U − Û‖₂/‖U‖₂) or "Linf" (Table 3: absolute errors, which
    the paper calls normalized but says are "not normalized"); ``method`` is "BSW" (the
    paper's "OUR") or "COT"; ``param`` is the kernel width as printed ("4h=0.04"), empty for
    COT.
    """

    table: int
    metric: str
    surface: str
    function: str
    method: str
    param: str
    n: int
    error: float

    @property
    def h(self) -> float | None:
        """The kernel width h (the paper prints 4h), or None for COT."""
        return float(self.param.removeprefix("4h=")) / 4 if self.param else None


def paper_tables() -> list[PaperCell]:
    """The 104 published cells of the paper's Tables 1–4, in the paper's order.

    Read from ``meshlap/data/bsw2008_tables.csv``, which ships with the package: the paper's
    values as printed, transcribed from its text. The paper does not state how its meshes were
    sampled, the noise of Table 4, nor which plane vertices were scored; :data:`VARIANTS`
    names the row of ours that measures each of these choices.

    Examples
    --------
    >>> cells = paper_tables()
    >>> len(cells), sorted({c.table for c in cells})
    (104, [1, 2, 3, 4])
    >>> c = [c for c in cells if (c.table, c.function, c.method, c.n) == (2, "x^2", "BSW", 16000)][0]
    >>> c.error, c.param, c.h
    (0.005, '4h=0.04', 0.01)
    """
    text = resources.files("meshlap").joinpath("data", "bsw2008_tables.csv").read_text(encoding="utf-8")
    return [PaperCell(int(row["table"]), row["metric"], row["surface"], row["function"], row["method"],
                      row["param"], int(row["n"]), float(row["error"]))
            for row in csv.DictReader(text.splitlines())]


#: Our table and error field in the metric of each of the paper's tables. Table 3 is in
#: absolute errors (the paper: "not normalized"), so it is compared with ``abs_linf``.
PAPER_METRICS = {1: ("plane", "l2"), 2: ("uniform", "l2"), 3: ("uniform", "abs_linf"), 4: ("noisy", "l2")}
#: For each of the paper's tables, our rows under other choices the paper leaves open, as
#: (our table, what the choice is): "plane-all", the plane scored over every vertex instead of
#: the interior; "plane-stratified", stratified instead of i.i.d. plane samples
#: (:func:`meshlap.shapes.plane`); "random", i.i.d. random sphere points instead of Fibonacci
#: ones; "noisy-strong", the noisy sphere with ``STRONG_NOISE`` instead of 0.05 edge lengths.
VARIANTS = {1: (("plane-all", "all vertices scored"), ("plane-stratified", "stratified plane")),
            2: (("random", "random sphere"),), 3: (("random", "random sphere"),),
            4: (("noisy-strong", f"noise {STRONG_NOISE:g}·a"),)}


