"""The fitted point-wise rows (`meshlap.corrections.rowchoice.choose_rows`, the default's
`pointwise="fit"` stage) of this checkout against another version's, in one process.

    git archive dd61feb | tar -x -C /tmp/base      # the version to compare with
    python benchmarks/bench_rowchoice.py --base /tmp/base --n 16000 --repeat 7
    python benchmarks/bench_rowchoice.py --base /tmp/base --n 16000 --noise 0.01

The base's modules of the stage (``MODULES``: rowchoice, highorder and the kernels they compile,
meshlap/_dense.py's small dense algebra) are loaded under other names beside this checkout's,
everything else shared; the two are run alternately on
`meshlap.shapes.sphere(n, kind="random", seed=0)` (radial noise of the given level, seed 1),
best of ``--repeat`` by CPU time (`time.process_time`: other processes' load counts less),
each stage timed through the progress callback. It prints whether the two gave the same L
and `RowChoice`, bit for bit. Prints only.

    python benchmarks/bench_rowchoice.py --base /tmp/base --cases 16000

runs bench_pointwise.py's inputs instead (sphere, torus and spot; clean, irregular and noisy;
its E2 = ‖Lf − Δf‖/‖Δf‖ over its two functions): E2 and CPU of both versions, whether L is the
same and at how many points the degree differs. bench_pointwise.py has the peers.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import re
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numba
import numpy as np

import meshlap
from meshlap.corrections import rowchoice

# in the order they import each other; a module the base does not have is skipped
MODULES = ("_dense", "corrections/_neighbours", "corrections/_fit_kernel", "corrections/highorder",
           "corrections/_ranks", "corrections/_gather", "corrections/_levels", "corrections/rowchoice")


def load_base(root: Path):
    """The base's rowchoice module, its relative imports made absolute (the stage's own modules
    as base_*, the rest of meshlap as this checkout's)."""
    present = [w for w in MODULES if (root / "meshlap" / f"{w}.py").exists()]
    own = "|".join(w.rsplit("/", 1)[-1] for w in present)
    for where in present:
        name = where.rsplit("/", 1)[-1]
        package = ".".join(["meshlap", *where.split("/")[:-1]])  # what "from .x" means in that file
        src = (root / "meshlap" / f"{where}.py").read_text()
        for pattern, repl in ((rf"^from \.\.?({own}) import", r"from base_\1 import"),
                              (r"^from \.\.(\w+) import", r"from meshlap.\1 import"),
                              (r"^from \.(\w+) import", rf"from {package}.\1 import")):
            src = re.sub(pattern, repl, src, flags=re.M)
        # numba caches compiled functions by their file: the rewritten modules get files of their own
        tag = hashlib.sha1(str(root.resolve()).encode()).hexdigest()[:12]
        path = Path(tempfile.gettempdir()) / f"meshlap-base-{tag}" / f"base_{name}.py"
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.exists() or path.read_text() != src:
            path.write_text(src)
        spec = importlib.util.spec_from_file_location(f"base_{name}", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[f"base_{name}"] = module
        spec.loader.exec_module(module)
    return sys.modules["base_rowchoice"]


def cases(base, n: int) -> None:
    """E2 of both versions' rows on bench_pointwise's inputs, one build each."""
    sys.path.insert(0, str(Path(__file__).parent))
    import bench_pointwise as bp

    all_cases = bp.sphere_cases(n) + bp.torus_cases(n) + bp.spot_cases()
    for module in (base, rowchoice):
        module.choose_rows(all_cases[0].V[:2000])  # compiles or loads the kernels
    for case in all_cases:
        out = {}
        for name, module in (("base", base), ("this", rowchoice)):
            t = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", meshlap.MeshWarning)
                L, choice = module.choose_rows(case.V)
            out[name] = (L, choice, time.process_time() - t)
            out[name] += (bp.e2(case, lambda f, L=L: L @ f),)
        (La, ca, ta, ea), (Lb, cb, tb, eb) = out["base"], out["this"]
        print(f"{case.shape} {case.condition}: E2 base {ea:.3g}, this {eb:.3g}; CPU {ta:.2f} -> {tb:.2f} s; "
              f"L identical {(La != Lb).nnz == 0}; degrees differ at {int((ca.degree != cb.degree).sum())}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path, required=True, help="a tree of the version to compare with")
    ap.add_argument("--n", type=int, default=16000)
    ap.add_argument("--noise", type=float, default=0.0, help="radial noise, relative to the radius")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--cases", type=int, metavar="N", help="bench_pointwise's inputs at N points instead")
    args = ap.parse_args()
    if args.cases:
        cases(load_base(args.base), args.cases)
        return
    V = meshlap.shapes.sphere(args.n, kind="random", seed=0)[0]
    if args.noise:
        V = V * (1 + args.noise * np.random.default_rng(1).standard_normal(len(V)))[:, None]
    versions = {"base": load_base(args.base), "this": rowchoice}
    for module in versions.values():
        module.choose_rows(V[:2000])  # compiles or loads the kernels
    best, stages, out = {}, {}, {}
    for _ in range(args.repeat):
        for name, module in versions.items():
            marks = []
            t = time.process_time()
            out[name] = module.choose_rows(V, progress=lambda stage, marks=marks: marks.append(
                (stage, time.process_time())))
            cpu = time.process_time() - t
            if cpu < best.get(name, np.inf):
                best[name] = cpu
                ends = [m[1] for m in marks[1:]] + [t + cpu]
                stages[name] = {stage: b - a for (stage, a), b in zip(marks, ends, strict=True)}
    (La, ca), (Lb, cb) = out["base"], out["this"]
    same_l = all(np.array_equal(getattr(La, a), getattr(Lb, a)) for a in ("data", "indices", "indptr"))
    same_c = all(np.array_equal(getattr(ca, a), getattr(cb, a))
                 for a in ("degree", "neighbors", "h", "noise", "scale", "predicted"))
    print(f"n = {args.n:,}, noise {args.noise}, {numba.get_num_threads()} threads, CPU s, "
          f"best of {args.repeat}: "
          f"base {best['base']:.3f}, this {best['this']:.3f}, base / this {best['base'] / best['this']:.2f}; "
          f"L identical: {same_l}, RowChoice identical: {same_c}")
    for name in versions:
        print(f"  {name}: " + ", ".join(f"{stage} {cpu:.3f}" for stage, cpu in stages[name].items()))


if __name__ == "__main__":
    main()
