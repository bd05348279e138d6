"""Every benchmark script once, at a small size, in a throw-away copy of the checkout: does it still
run? Two had stopped (bench_eigs.py called a helper that had moved; ``bench_real.py --render``
read a new CSV column as text) while their RESULTS sections went stale.

    python benchmarks/smoke.py                      # all (about 14 minutes on 2 cores)
    python benchmarks/smoke.py --only eigs,real     # names without bench_ and .py

Each script runs in its own process from a temporary copy of this checkout (what it writes lands
there, never in RESULTS.md), with the arguments below (``--no-write`` where the script has it).
The corpus scripts need ``$MESHLAP_CORPUS`` (bench_real.py's corpus) and are skipped without it;
the MPI ones need mpi4py and petsc4py. Exit status 1 when any script fails; prints each one's
return code, time and, on failure, its last lines. Timings are meaningless here.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

#: script → arguments; {base} is the copy of this checkout the scripts run from (the before/after
#: scripts compare it with itself), {out} a scratch folder
RUNS: dict[str, list[str]] = {
    "bench_accuracy.py": ["--no-write"],
    "bench_assembly.py": ["--quick", "--no-write"],
    "bench_cloud_cap.py": [],
    "bench_cloud_grids.py": ["--no-write"],
    "bench_clusters.py": ["--n", "3000", "--mesh-n", "800", "--no-write"],
    "bench_conventions.py": ["--n", "2000", "--repeat", "1", "--no-write"],
    "bench_curves.py": ["--quick", "--no-write"],
    "bench_degenerate.py": ["--no-write"],
    "bench_distributed.py": ["--quick"],
    "bench_eigcheck.py": ["--n", "300", "--no-write"],
    "bench_eigs.py": ["--quick"],
    "bench_factor.py": ["--quick", "--no-write"],
    "bench_fallback.py": ["--quick"],
    "bench_first_call.py": ["--repeat", "1", "--src", "{base}"],
    "bench_fit_order.py": ["--n", "2000", "--repeat", "1"],
    "bench_grid_rows.py": ["--baseline", "{base}/meshlap/assembly/grid.py", "--n", "3000", "--repeat", "1"],
    "bench_kernel_rows.py": ["--n", "3000", "--repeat", "1"],
    "bench_loops.py": ["--no-write"],
    "bench_narrow.py": ["--n", "1000", "--no-write"],
    "bench_matrix_free.py": ["--n", "5000", "--repeat", "1", "--max-n", "1000"],
    "bench_pipeline.py": ["--quick"],
    "bench_pointcloud.py": ["--accuracy", "--n", "2000", "--no-write"],
    "bench_pointwise.py": ["--n", "2000", "--no-write"],
    "bench_psd.py": [],
    "bench_quadrature.py": ["--no-write"],
    "bench_real.py": ["--only", "cow,fuze,octopus-tet", "--no-write"],
    "bench_real_uses.py": ["--only", "cow,fandisk-coarse", "--no-write"],
    "bench_cloud_stars.py": ["--only", "fuze", "--no-write"],
    "bench_cloud_boundary.py": ["--only", "beetle-c3", "--spheres", "2000", "--no-write"],
    "bench_rowchoice.py": ["--base", "{base}", "--n", "2000", "--repeat", "1"],
    "bench_scale.py": ["--n", "5000", "--no-write"],
    "bench_seams.py": ["--no-write"],
    "bench_smoothing.py": ["--no-write"],
    "bench_spectra.py": ["--quick"],
    "bench_tol.py": ["--quick"],
    "bench_uses.py": ["--sizes", "2000", "--no-write"],
    "bench_volume_eigs.py": ["--quick", "--no-write", "--limit", "120"],
    "cloud_neighbors.py": ["--only", "cow", "--counts", "16"],
    "profile_check.py": ["--n", "5000"],
    "reproduce_tables.py": ["--quick", "--out", "{out}"],
    "touching_oracle.py": ["cow"],
}
#: a second run of a script with other arguments (a mode of its own)
AGAIN: dict[str, list[str]] = {
    "bench_volume_eigs.py": ["--solves", "--quick", "--no-write", "--limit", "120"],
}
#: scripts that read bench_real.py's corpus
CORPUS = {"bench_cloud_boundary.py", "bench_cloud_stars.py", "bench_factor.py", "bench_loops.py",
          "bench_real.py", "bench_real_uses.py", "bench_seams.py", "bench_smoothing.py", "cloud_neighbors.py",
          "touching_oracle.py"}
#: not benchmarks: helpers the others import, this script, the corpus builder (it needs clones)
NOT_RUN = {"real_corpus.py", "results_file.py", "smoke.py", "build_corpus.py"}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", default="", help="comma-separated names, e.g. eigs,real,cloud_neighbors")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per script")
    args = ap.parse_args(argv)
    wanted = set()
    for word in filter(None, args.only.split(",")):
        found = [c for c in (word, f"{word}.py", f"bench_{word}.py") if c in RUNS]
        if not found:
            ap.error(f"no such script: {word}")
        wanted.add(found[0])
    wanted = wanted or set(RUNS)
    failed = []
    with tempfile.TemporaryDirectory() as tmp:
        base, out = Path(tmp) / "checkout", Path(tmp) / "out"
        skip = shutil.ignore_patterns(".git", "__pycache__", "*_cache", ".hypothesis", "corpus", "_build",
                                      "notebooks", "*.egg-info")
        shutil.copytree(ROOT, base, ignore=skip)  # the scripts read tests/data beside them
        bench = base / "benchmarks"
        out.mkdir()
        for name in sorted(wanted):
            why = None
            if name in CORPUS and not os.environ.get("MESHLAP_CORPUS"):
                why = "no $MESHLAP_CORPUS"
            elif name == "bench_distributed.py" and not all(
                    importlib.util.find_spec(m) for m in ("mpi4py", "petsc4py")):
                why = "no mpi4py/petsc4py"
            if why:
                print(f"{name:24s} skipped ({why})", flush=True)
                continue
            for extra in [RUNS[name]] + ([AGAIN[name]] if name in AGAIN else []):
                cmd = [sys.executable, str(bench / name)] + [a.format(base=base, out=out) for a in extra]
                start = time.perf_counter()
                try:
                    run = subprocess.run(cmd, cwd=tmp, capture_output=True, text=True, timeout=args.timeout)
                    rc, tail = run.returncode, (run.stdout + run.stderr).strip().splitlines()[-6:]
                except subprocess.TimeoutExpired:
                    rc, tail = "timeout", []
                print(f"{name:24s} rc={rc} {time.perf_counter() - start:6.1f} s", flush=True)
                if rc != 0:
                    failed.append(name)
                    print("    " + "\n    ".join(tail), flush=True)
    print(f"{len(failed)} failed" + (f": {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
