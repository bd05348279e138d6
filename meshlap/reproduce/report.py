"""The reproduction run as markdown tables and a convergence plot."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .. import shapes
from .paper import PAPER_METRICS, VARIANTS, paper_tables
from .results import Reproduction
from .settings import _SPHERE_TABLES, PLANE_H, PLANE_MARGIN, SPHERE_H, STRONG_NOISE

__all__ = ["format_markdown", "plot_convergence"]


# -- output --------------------------------------------------------------------------------
def _row_table(rep: Reproduction, table: str, h: float, norm: str, methods: Sequence[str]) -> list[str]:
    # the floor (BSW rows) is L_h's error at the points of the largest mesh
    ns = rep.ns
    head = "| function | method | " + " | ".join(f"n = {n:,}" for n in ns) + " | floor (n → ∞) |"
    lines = [head, "|" + "---|" * (3 + len(ns))]
    functions = list(dict.fromkeys(r.function for r in rep.records if r.table == table))
    for fn in functions:
        for m in methods:
            rows = rep.select(table=table, h=h, function=fn, method=m)
            if not rows:
                continue
            cells = [f"{getattr(r, norm):.4f}" for r in rows]
            fl = getattr(rows[-1], f"floor_{norm}")
            floor = "–" if math.isnan(fl) else f"{fl:.4f}"
            lines.append(f"| {fn} | {m} | " + " | ".join(cells) + f" | {floor} |")
    return lines


def _disc_table(rep: Reproduction) -> list[str]:
    ns = rep.ns
    lines = ["| surface | h | function | " + " | ".join(f"n = {n:,}" for n in ns) + " |",
             "|" + "---|" * (3 + len(ns))]
    keys = dict.fromkeys((r.table, r.h, r.function) for r in rep.records if r.method == "BSW")
    for table, h, fn in keys:
        e = rep.errors(table, fn, "BSW", "disc_l2", h=h)
        lines.append(f"| {table} | {h:g} | {fn} | " + " | ".join(f"{v:.4f}" for v in e) + " |")
    return lines


_PAPER_TITLES = {
    1: "Table 1 — plane [-1, 1]², normalized L2 error (ours: interior vertices, margin 5√h)",
    2: "Table 2 — uniform sphere, normalized L2 error",
    3: "Table 3 — uniform sphere, absolute L∞ error max|Lf − Δf| (the paper's values are not normalized)",
    4: "Table 4 — noisy sphere, normalized L2 error",
}


def _paper_section(rep: Reproduction) -> list[str]:
    # each published cell beside ours, grouped like the paper's tables, then the variant rows
    if not rep.beside:
        return []
    ns = rep.ns
    index = {(r.table, r.h, r.function, r.method, r.n): r for r in rep.records + rep.variants}
    L = ["## The paper beside ours", "",
         f"The paper's published cells (`meshlap.reproduce.paper_tables()`, {len(paper_tables())} in "
         "Tables 1–4, as printed) beside ours at the same n and in the paper's metric, with the ratio "
         "ours/paper (below 1: our error is smaller); \"floor of L_h\" is the error of the continuous "
         "operator at this h (BSW's limit as n → ∞, see below) in the same metric. Table 3's published "
         "values are absolute errors max|Lf − Δf| (the paper: \"not normalized\"), so ours are absolute "
         "there too; the normalized "
         "L∞ table further down is not comparable with the paper's. The paper's COT row of Table 1 "
         "has no h: it stands beside our COT on the vertices scored at each h. The rows \"ours, …\" "
         "measure a choice the paper leaves open (`VARIANTS`): the plane scored over all vertices, "
         "and the plane from stratified samples (an m × m grid, m = round(√n), each interior node "
         "moved to a uniform point of its cell) instead of i.i.d. ones (Table 1); i.i.d. random "
         "sphere points instead of Fibonacci ones (Tables 2–3); noise of "
         f"{STRONG_NOISE:g} instead of {shapes.NOISE_FRACTION:g} edge lengths (Table 4).", "",
         "| paper table | method | cells beside ours | ours smaller | ours larger | median ours/paper "
         "| min – max | median ours/paper, other choice |", "|---|---|---|---|---|---|---|---|"]
    for t in sorted({b.paper.table for b in rep.beside}):
        for method in ("BSW", "COT"):
            r = np.array([b.ratio for b in rep.beside if (b.paper.table, b.paper.method, b.variant)
                          == (t, method, "")])
            alts = []
            for _, variant in VARIANTS[t]:
                v = [b.ratio for b in rep.beside if (b.paper.table, b.paper.method, b.variant)
                     == (t, method, variant)]
                if v:
                    alts.append(f"{np.median(v):.3g} ({variant})")
            if len(r):
                alt = "; ".join(alts) or "–"
                L.append(f"| {t} | {method} | {len(r)} | {int((r < 1).sum())} | {int((r > 1).sum())} | "
                         f"{np.median(r):.3g} | {r.min():.3g} – {r.max():.3g} | {alt} |")
    L.append("")
    head = ["| function | method | row | " + " | ".join(f"n = {n:,}" for n in ns) + " |",
            "|" + "---|" * (3 + len(ns))]
    for t in sorted({b.paper.table for b in rep.beside}):
        L += [f"### {_PAPER_TITLES[t]}", ""]
        ours_table, metric = PAPER_METRICS[t]
        for h in sorted({b.h for b in rep.beside if b.paper.table == t}):
            if t == 1:
                L += [f"4h = {4 * h:.2f} (h = {h:g})", ""]
            L += head
            cells = [b for b in rep.beside if b.paper.table == t and b.h == h]
            for fn, method in dict.fromkeys((b.paper.function, b.paper.method) for b in cells):
                paper = {b.paper.n: b.paper.error for b in cells
                         if (b.paper.function, b.paper.method) == (fn, method)}
                for table, suffix in ((ours_table, ""), *((v, f", {a}") for v, a in VARIANTS[t])):
                    rows = [index.get((table, h, fn, method, n)) for n in ns]
                    if not any(rows):
                        continue
                    ours = [math.nan if r is None else getattr(r, metric) for r in rows]
                    ratio = [o / paper[n] if n in paper else math.nan for o, n in zip(ours, ns, strict=True)]
                    lines = [("ours", [_cell(o, ".4g" if o >= 10 else ".4f") for o in ours]),
                             ("paper", [f"{paper[n]:g}" if n in paper else "–" for n in ns]),
                             ("ours/paper", [_cell(r, ".3g") for r in ratio])]
                    if method == "BSW" and not suffix:
                        # what BSW tends to as n → ∞ at this h, in the same metric
                        floor = [math.nan if r is None else getattr(r, f"floor_{metric}") for r in rows]
                        lines.append(("floor of L_h", [_cell(f, ".4f") for f in floor]))
                    # a variant row: ours and the ratio only
                    for label, row in lines if not suffix else [lines[0], lines[2]]:
                        L.append(f"| {fn} | {method} | {label}{suffix} | " + " | ".join(row) + " |")
            L.append("")
    return L


def _cell(x: float, spec: str) -> str:
    return "–" if math.isnan(x) else format(x, spec)


def format_markdown(rep: Reproduction, command: str = "") -> str:
    """The tables and checks as markdown (also readable as plain text)."""
    methods = list(dict.fromkeys(r.method for r in rep.records))
    L: list[str] = ["# Belkin–Sun–Wang (SoCG 2008), Tables 1–4 reproduced", ""]
    if command:
        L += ["Made by:", "", "```bash", command, "```", ""]
    L += [
        f"Vertices n = {', '.join(f'{n:,}' for n in rep.ns)}; run time {rep.seconds:.0f} s. "
        "Errors are normalized: L2 = ‖Lf − Δf‖₂/‖Δf‖₂, L∞ = max|Lf − Δf| / max|Δf| over the scored "
        "vertices. BSW = meshlap.laplacian (tol 1e-8), COT = cotangent + Voronoi mass"
        + (", IDT = intrinsic Delaunay (robust-laplacian), graph = uniform graph Laplacian"
           if len(methods) > 2 else "") + ". The paper's published numbers stand beside ours in the "
        "first section; docs/reproduction.md says why ours differ where they are larger.",
        "",
    ]
    L += _paper_section(rep)
    plane_hs = sorted({r.h for r in rep.records if r.table == "plane"})
    if plane_hs:
        L += ["## Table 1 — plane [-1, 1]², normalized L2 error", ""]
        for h in plane_hs:
            scored = rep.select(table="plane", h=h, method="BSW")
            counts = ", ".join(f"{r.scored}" for r in scored[:: max(1, len(set(x.function for x in scored)))])
            L += [f"4h = {4 * h:.2f} (h = {h:g}); scored: vertices with max(|x|, |y|) ≤ "
                  f"1 − {PLANE_MARGIN:g}√h = {1 - PLANE_MARGIN * math.sqrt(h):.2f} ({counts} of them)", ""]
            L += _row_table(rep, "plane", h, "l2", methods) + [""]
    for table, title in _SPHERE_TABLES.items():
        hs = sorted({r.h for r in rep.records if r.table == table})
        for h in hs:
            norms = ("l2", "linf") if table == "uniform" else ("l2",)
            for norm in norms:
                what = "normalized L2 error" if norm == "l2" else "normalized L∞ error (Table 3)"
                L += [f"## {title}: {what}, h = {h:g}", ""]
                L += _row_table(rep, table, h, norm, methods) + [""]
    L += ["The floor is the error of the continuous heat operator L_h at the same points, in closed "
          "form (`meshlap.reproduce.square_heat_limit` on the square, boundary truncation included; "
          "`sphere_bias`/`sphere_heat_limit` on the sphere): at fixed h, BSW converges to L_h, not "
          "to Δ, so its error tends to the floor, not to 0. The distance of BSW to L_h itself, "
          "‖Lf − L_h f‖₂/‖Δf‖₂:", ""]
    L += _disc_table(rep) + ["", "## Claims checked on these numbers", ""]
    for c in rep.checks:
        L.append(f"- [{'x' if c.holds else ' '}] **{c.claim}** — {'holds' if c.holds else 'DOES NOT HOLD'}: "
                 f"{c.detail}")
    L.append("")
    return "\n".join(L)


def plot_convergence(rep: Reproduction, path: Path) -> Path:
    """Log-log error against n for the main tables (BSW solid, COT dashed), saved as PNG.

    Where the paper has the panel's table in the same metric (plane, uniform sphere L2, noisy
    sphere), its published values are drawn as × (BSW) and + (COT) in the function's colour.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    panels = [("plane", PLANE_H[1], "l2", "plane, 4h = 0.04, L2"),
              ("uniform", SPHERE_H, "l2", "uniform sphere, L2"),
              ("uniform", SPHERE_H, "linf", "uniform sphere, L∞"),
              ("noisy", SPHERE_H, "l2", "noisy sphere, L2"),
              ("nonuniform", SPHERE_H, "l2", "non-uniform sphere, L2"),
              ("random", SPHERE_H, "l2", "random sphere, L2")]
    panels = [p for p in panels if rep.select(table=p[0], h=p[1])]
    cols = 3
    rows = max(1, math.ceil(len(panels) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
    ns = np.array(rep.ns)
    for ax, (table, h, norm, title) in zip(axes.ravel(), panels, strict=False):
        functions = list(dict.fromkeys(r.function for r in rep.select(table=table, h=h)))
        for k, fn in enumerate(functions):
            color = f"C{k}"
            for method, style in (("BSW", "-o"), ("COT", "--s")):
                e = rep.errors(table, fn, method, norm, h=h)
                if len(e):
                    ax.loglog(ns, e, style, color=color, ms=4, label=f"{method} {fn}")
            for method, marker in (("BSW", "x"), ("COT", "+")):
                paper = sorted((b.paper.n, b.paper.error) for b in rep.beside if not b.variant
                               and (b.table, b.h, b.paper.function, b.paper.method) == (table, h, fn, method)
                               and PAPER_METRICS[b.paper.table][1] == norm)
                if paper:
                    ax.loglog(*zip(*paper, strict=True), marker, color=color, ms=7, ls="none",
                              label=f"paper {method} {fn}" if k == 0 else None)
            fl = rep.select(table=table, h=h, function=fn, method="BSW")
            # a floor of (nearly) 0, e.g. for f = x on the sphere, has no place on a log axis
            if fl and getattr(fl[-1], f"floor_{norm}") > 1e-6:
                ax.axhline(getattr(fl[-1], f"floor_{norm}"), color=color, lw=0.8, ls=":")
        ax.set_title(title, fontsize=10)
        # label the measured n only: log-axis minor labels (2×10³, 3×10³, ...) overlap
        ax.set_xticks(ns, [f"{n:,}" for n in ns])
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel("vertices n")
        ax.set_ylabel("normalized error")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6, ncol=2, framealpha=0.7)
    for ax in axes.ravel()[len(panels):]:
        ax.axis("off")
    fig.suptitle("BSW (solid) vs COT (dashed); dotted: the BSW floor at fixed h; "
                 "× / +: the paper's published BSW / COT", fontsize=11)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
