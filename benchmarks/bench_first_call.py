"""The first build on a fresh numba cache: CPU time, and the compile time of each kernel.

    python benchmarks/bench_first_call.py [--repeat 3] [--src DIR]

Each case runs in its own process with an empty cache folder (XDG_CACHE_HOME), as on a new
machine: a 500-vertex sphere (``meshlap.shapes.sphere(500, seed=0)``) with the default
operator (linear FEM) and with ``operator="kernel"``, and a 500-point cloud, each built up to
its symmetric pencil (``op.assemble()``); each twice, alternately: from
the sources as they are (an editable install: the kernels compile on first use), and from a
copy of the package with the kernels a wheel ships (compiled once at the start by
``meshlap._prebuilt.build``, the build step of ``pip install .``, whose CPU time is printed
too). Figures are process CPU time (``time.process_time``), the best of ``--repeat`` runs
and their range, the wall time of the best, and the load average over the runs: on a shared
machine wall time measures the neighbours, and even CPU time grows with the load. ``--src``
times another checkout of meshlap (its root folder), e.g. an older commit for a
before/after comparison in the same session (one without ``meshlap/_prebuilt.py`` is timed
from its sources only).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CHILD = """
import json, sys, threading, time
from collections import defaultdict
from numba.core import event

spent, local = defaultdict(float), threading.local()

class Kernels(event.Listener):  # CPU seconds of each outermost compilation
    def on_start(self, ev):
        local.stack = getattr(local, "stack", []) + [time.process_time()]
    def on_end(self, ev):
        t = time.process_time() - local.stack.pop()
        if not local.stack:
            f = ev.data["dispatcher"].py_func
            spent[f"{f.__module__}.{f.__name__}"] += t

event.register("numba:compile", Kernels())
t0 = time.process_time()
import meshlap
t1 = time.process_time()
case = sys.argv[1]
if case == "cloud":
    P = meshlap.samples.sphere_points(500)
    t1, w1 = time.process_time(), time.perf_counter(); meshlap.point_cloud_laplacian(P).assemble()
else:
    V, F = meshlap.shapes.sphere(500, seed=0)
    t1, w1 = time.process_time(), time.perf_counter()
    meshlap.laplacian(V, F, **({"operator": "kernel"} if case == "mesh-kernel" else {})).assemble()
t2, w2 = time.process_time(), time.perf_counter()
print(json.dumps(dict(build=t2 - t1, wall=w2 - w1, kernels=spent)))
"""

CASES = {"mesh": "default operator, 500-vertex sphere", "mesh-kernel": 'operator="kernel", 500-vertex sphere',
         "cloud": "default operator, 500-point cloud"}


def run(case: str, src: Path) -> dict:
    with tempfile.TemporaryDirectory() as cache:
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        env.update(XDG_CACHE_HOME=cache, PYTHONPATH=str(src))
        done = subprocess.run([sys.executable, "-c", CHILD, case], env=env, capture_output=True, text=True,
                              check=True, timeout=900, cwd=src)
    return json.loads(done.stdout.splitlines()[-1])


def shipped_copy(src: Path, where: Path) -> Path | None:
    """The package of ``src`` as a wheel installs it, with the kernels its build step compiles."""
    if not (src / "meshlap" / "_prebuilt.py").exists():
        return None
    skip = shutil.ignore_patterns("__pycache__", "_kernels")
    shutil.copytree(src / "meshlap", where / "build" / "meshlap", ignore=skip)
    sys.path.insert(0, str(src))
    from meshlap import _prebuilt

    cpu, wall = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
    _prebuilt.build(where / "build" / "meshlap")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    spent = after.ru_utime + after.ru_stime - cpu.ru_utime - cpu.ru_stime
    print(f"build step (meshlap._prebuilt.build): {spent:.1f} s CPU, "
          f"{time.perf_counter() - wall:.1f} s wall\n")
    # installed elsewhere, with fresh file times, as pip does
    shutil.copytree(where / "build" / "meshlap", where / "site" / "meshlap", copy_function=shutil.copy)
    return where / "site"


def cell(runs: list[dict]) -> tuple[str, dict]:
    best = min(runs, key=lambda r: r["build"])
    worst = max(r["build"] for r in runs)
    return f"{best['build']:.2f} ({best['build']:.2f}-{worst:.2f}), wall {best['wall']:.2f}", best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--src", type=Path, default=Path(__file__).resolve().parents[1])
    args = ap.parse_args()
    loads = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory() as where:
        site = shipped_copy(args.src.resolve(), Path(where))
        print(f"| case | compiling on first use: CPU s (best of {args.repeat}, range), wall | kernels "
              "compiled in the best (CPU s) | with the shipped kernels: CPU s, wall | kernels compiled |")
        print("|---|---|---|---|---|")
        for case, what in CASES.items():
            runs: dict[str, list[dict]] = {"src": [], "site": []}
            for _ in range(args.repeat):  # alternately, so that both see the same load
                runs["src"].append(run(case, args.src))
                if site is not None:
                    runs["site"].append(run(case, site))
                loads.append(os.getloadavg()[0])
            compiled, best = cell(runs["src"])
            kernels = ", ".join(f"{k.split('.')[-1]} {v:.1f}" for k, v in
                                sorted(best["kernels"].items(), key=lambda kv: -kv[1]))
            shipped, best = cell(runs["site"]) if site is not None else ("-", {"kernels": {}})
            print(f"| {what} | {compiled} | {kernels} | {shipped} | {', '.join(best['kernels']) or 'none'} |")
    print(f"\nload average over the runs: {min(loads):.1f}-{max(loads):.1f} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
