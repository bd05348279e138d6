"""The first build on a fresh numba cache: CPU time, and the compile time of each kernel.

    python benchmarks/bench_first_call.py [--repeat 3] [--src DIR]

Each case runs in its own process with an empty cache folder (XDG_CACHE_HOME), as on a new
machine: a 500-vertex sphere (``meshlap.shapes.sphere(500, seed=0)``) with the default
operator and with ``pointwise="fit"``, and a 500-point cloud. Figures are process CPU time
(``time.process_time``), the best of ``--repeat`` runs and their range, and the load average
over the runs: on a shared machine wall time measures the neighbours, and even CPU time grows
with the load. ``--src`` times another checkout of meshlap (its root folder), e.g.
an older commit for a before/after comparison in the same session.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
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
    t1 = time.process_time(); meshlap.point_cloud_laplacian(P)
else:
    V, F = meshlap.shapes.sphere(500, seed=0)
    t1 = time.process_time(); meshlap.laplacian(V, F, **({"pointwise": "fit"} if case == "mesh-fit" else {}))
t2 = time.process_time()
print(json.dumps(dict(build=t2 - t1, kernels=spent)))
"""

CASES = {"mesh": "default operator, 500-vertex sphere", "mesh-fit": 'pointwise="fit", 500-vertex sphere',
         "cloud": "default operator, 500-point cloud"}


def run(case: str, src: Path) -> dict:
    with tempfile.TemporaryDirectory() as cache:
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        env.update(XDG_CACHE_HOME=cache, PYTHONPATH=str(src))
        done = subprocess.run([sys.executable, "-c", CHILD, case], env=env, capture_output=True, text=True,
                              check=True, timeout=900)
    return json.loads(done.stdout.splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--src", type=Path, default=Path(__file__).resolve().parents[1])
    args = ap.parse_args()
    loads = [os.getloadavg()[0]]
    print(f"| case | first build, CPU s (best of {args.repeat}, range) | kernels in the best (CPU s) |")
    print("|---|---|---|")
    for case, what in CASES.items():
        runs = []
        for _ in range(args.repeat):
            runs.append(run(case, args.src))
            loads.append(os.getloadavg()[0])
        best = min(runs, key=lambda r: r["build"])
        worst = max(r["build"] for r in runs)
        kernels = ", ".join(f"{k.split('.')[-1]} {v:.1f}" for k, v in
                            sorted(best["kernels"].items(), key=lambda kv: -kv[1]))
        print(f"| {what} | {best['build']:.1f} ({best['build']:.1f}-{worst:.1f}) | {kernels} |")
    print(f"\nload average over the runs: {min(loads):.1f}-{max(loads):.1f} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
