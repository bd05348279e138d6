"""Ten eigenpairs of a tetrahedral volume: LOBPCG preconditioned by multigrid against shift-invert
on a sparse factorization, and LaPy's solver beside them.

    python benchmarks/bench_volume_eigs.py                    # RESULTS.md
    python benchmarks/bench_volume_eigs.py --quick --no-write
    python benchmarks/bench_volume_eigs.py --extra carotid.vtk ironProt.vtk   # any volume files
    python benchmarks/bench_volume_eigs.py --solves           # Poisson solves and heat steps

Each row is ``spectral.eigs(meshlap.laplacian(V, T, k=3), 10)`` (linear FEM, verified pairs) with
``method="lobpcg"`` (meshlap._multigrid's V-cycle as preconditioner, above
``meshlap._multigrid.MAX_FACTOR_WORK`` counted multiply-adds of factoring, and shift-invert after
all where the V-cycle stalls: ``_multigrid.Stall``; the corpus's notch_stress and can volumes are
also refined once, 8 tetrahedra each, past the bound) and
``method="shift-invert"`` (SuperLU), and LaPy's
``Solver(TetMesh).eigs`` (its own linear FEM, scipy's or CHOLMOD's factorization), each in a
process of its own so that its peak memory is its own: wall seconds of the solve (the build
apart), peak resident memory, and the largest relative error of eigenvalues 1-9 against the
exact Neumann cube (π²(a² + b² + c²)) or, on other volumes, against shift-invert's (LaPy's where
shift-invert ran out of time: the same linear FEM and lumped mass). A run past ``--limit``
seconds is stopped and shown as such. Files given with ``--extra`` (real volumes, such as
pyvista/vtk-data's voxel images, split into tetrahedra by VTK) get a table of their own.

``--solves`` times, on the same cubes, a Poisson solve (Δφ = f, φ = 0 on the face z = 0,
insulated elsewhere; φ = cos πx cos πy sin(πz/2) exactly) and an implicit heat step
(``(M - τS) u = M f``, τ = 0.01), each with its set-up: ``solver="auto"`` (conjugate gradient
with multigrid above ``MAX_FACTOR_WORK``), ``solver="direct"`` (SuperLU), and LaPy's
``Solver.poisson`` and ``heat.diffusion`` (a step of the same kind, its own factorization).
Error: the Poisson solution's largest error against the exact φ, relative to its largest value;
the heat step's largest difference from the direct step's, relative.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import real_corpus as rc  # noqa: E402
from results_file import write_section  # noqa: E402

K = 10


def _volume(spec: str) -> tuple[np.ndarray, np.ndarray]:
    import meshlap

    if spec.startswith("refined:"):  # each tetrahedron split into 8 at its edges' midpoints
        return rc.refine(*_volume(spec[8:]), 1)
    if spec.startswith("cube:"):
        return meshlap.samples.cube_tetrahedra(int(spec[5:]))
    if spec.startswith("corpus:"):
        folder = rc.corpus_dir(None)
        entry = next(e for e in rc.manifest() if e["name"] == spec[7:])
        mesh = rc.load(folder / entry["file"], entry["format"])
        return mesh.Vw, np.asarray(mesh.Cw)
    P, cells, _ = meshlap.inputs.read_input(spec)
    return P, np.asarray(cells)


def _exact_poisson(V: np.ndarray) -> np.ndarray:
    return np.cos(np.pi * V[:, 0]) * np.cos(np.pi * V[:, 1]) * np.sin(0.5 * np.pi * V[:, 2])


def _solve_child(V: np.ndarray, T: np.ndarray, task: str, solver: str) -> tuple[float, np.ndarray]:
    # seconds of one Poisson solve or heat step with its set-up, and its solution
    import meshlap
    from meshlap import heat, solve

    phi = _exact_poisson(V)
    f = -2.25 * np.pi**2 * phi  # Δφ
    bottom = np.flatnonzero(V[:, 2] < 1e-9)
    if solver == "lapy":
        from lapy import Solver, TetMesh
        from lapy import heat as lapy_heat

        tet = TetMesh(V, T)
        tet.orient_()
        t = time.perf_counter()
        if task == "poisson":  # LaPy's A x = B h, A its stiffness: h = -f
            u = Solver(tet, lump=True).poisson(-f, dtup=(bottom, np.zeros(len(bottom))))
        else:  # a step from vertex 0 of the same time, τ = m ē²
            edges = np.linalg.norm(V[T[:, 0]] - V[T[:, 1]], axis=1).mean()
            u = lapy_heat.diffusion(tet, 0, m=0.01 / edges**2)
        return time.perf_counter() - t, u
    op = meshlap.laplacian(V, T, k=3)
    op.assemble()
    t = time.perf_counter()
    if task == "poisson":
        u = solve.PoissonSolver(op, bottom, solver=solver).solve(-op.mass * f)
    else:
        u = heat.ImplicitHeat(op, 0.01, solver=solver)(np.cos(np.pi * V[:, 0]) * np.cos(np.pi * V[:, 1]))
    return time.perf_counter() - t, u


def _child(spec: str, solver: str) -> None:
    # one solve in this process: prints a JSON line
    import meshlap

    warnings.simplefilter("ignore")
    V, T = _volume(spec)
    if ":" in solver:  # --solves: task:solver
        try:
            seconds, u = _solve_child(V, T, *solver.split(":"))
        except ImportError:
            print(json.dumps({"missing": "lapy"}))
            return
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
        exact = _exact_poisson(V)
        err = float(np.abs(u - exact).max() / np.abs(exact).max())
        print(json.dumps({"n": len(V), "seconds": seconds, "rss": rss, "err": err,
                          "sample": np.asarray(u)[:: max(1, len(V) // 500)].tolist()}))
        return
    if solver == "lapy":
        try:
            from lapy import Solver, TetMesh
        except ImportError:  # a peer of the bench extra
            print(json.dumps({"missing": "lapy"}))
            return

        tet = TetMesh(V, T)
        tet.orient_()
        t = time.perf_counter()
        lam = Solver(tet, lump=True).eigs(K)[0]
    else:
        op = meshlap.laplacian(V, T, k=3)
        op.assemble()
        t = time.perf_counter()
        lam = meshlap.spectral.eigs(op, K, method=solver)[0]
    seconds = time.perf_counter() - t
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # GiB
    print(json.dumps({"n": len(V), "seconds": seconds, "rss": rss, "lam": np.sort(lam).tolist()}))


def run(spec: str, solver: str, limit: float) -> dict | None:
    cmd = [sys.executable, __file__, "--child", spec, solver]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=limit, env=os.environ.copy())
    except subprocess.TimeoutExpired:
        return None
    lines = [s for s in out.stdout.splitlines() if s.startswith("{")]
    if not lines:
        raise RuntimeError(f"{spec} {solver}: {out.stderr[-2000:]}")
    return json.loads(lines[-1])


def error(lam: list, ref: np.ndarray) -> float:
    lam = np.asarray(lam)
    return float(np.max(np.abs(lam[1:K] - ref[1:K]) / ref[1:K]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--limit", type=float, default=600.0)
    ap.add_argument("--extra", nargs="*", default=[])
    ap.add_argument("--solves", action="store_true", help="Poisson solves and heat steps instead")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        _child(*args.child)
        return
    if args.solves:
        solves(args)
        return
    import meshlap
    from meshlap import _multigrid

    cubes = (12, 20) if args.quick else (20, 30, 40, 50)
    specs = [f"cube:{n}" for n in cubes]
    if not args.quick and rc.corpus_dir(None) is not None:
        specs += [f"corpus:{e['name']}" for e in rc.manifest() if "tet" in e["kind"].split()]
        # graded FEA volumes refined past the factoring bound, where the V-cycle stalls
        specs += ["refined:corpus:notch-tet", "refined:corpus:can-tet"]
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rows, extra_rows = [], []
    for spec in specs + args.extra:
        res = {s: run(spec, s, args.limit) for s in ("lobpcg", "shift-invert", "lapy")}
        exact = meshlap.samples.cube_eigenvalues(K) if spec.startswith("cube:") else None
        other = res["shift-invert"] or (res["lapy"] if res["lapy"] and "lam" in res["lapy"] else None)
        ref = exact if exact is not None else None if other is None else np.asarray(other["lam"])
        n = next((r["n"] for r in res.values() if r and "n" in r), None)
        cells = []
        for s in ("lobpcg", "shift-invert", "lapy"):
            r = res[s]
            if r is None:
                cells.append(f"> {args.limit:.0f} s | – | –")
            elif "missing" in r:
                cells.append("not installed | – | –")
            else:
                err = "–" if ref is None else f"{100 * error(r['lam'], ref):.3g}%"
                cells.append(f"{r['seconds']:.2f} | {r['rss']:.2f} | {err}")
        name = f"cube {spec[5:]}³" if spec.startswith("cube:") else spec.split(":")[-1] if ":" in spec \
            else Path(spec).name
        name += " refined" if spec.startswith("refined:") else ""
        (rows if spec in specs else extra_rows).append(f"| {name} | {n:,} | " + " | ".join(cells) + " |")
        print((rows + extra_rows)[-1], flush=True)
    extra = f" --extra {' '.join(Path(x).name for x in args.extra)}" if args.extra else ""
    head = [f"Command: `python benchmarks/bench_volume_eigs.py{' --quick' if args.quick else ''}"
            f" --limit {args.limit:g}{extra}` ({started}, 2 shared cores). `method=\"lobpcg\"` is "
            f"preconditioned by multigrid above {_multigrid.MAX_FACTOR_WORK:.0e} counted multiply-adds of "
            "factoring (the default there; shift-invert after all where the V-cycle stalls, "
            "`_multigrid.Stall`), by the exact factor below; \"refined\": each tetrahedron split into 8. "
            "Seconds of the solve (wall), peak resident GiB of its process, "
            "largest relative error of eigenvalues 1-9 (the cube's exact Neumann values; elsewhere "
            "shift-invert's, or LaPy's where shift-invert ran out of time).", "",
            "| volume | vertices | lobpcg s | GiB | error | shift-invert s | GiB | error "
            "| LaPy s | GiB | error |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    if not args.no_write:
        write_section("bench_volume_eigs.py", head[:1])
        write_section("Tetrahedral cubes and the corpus's volumes", head[2:] + rows)
        if extra_rows:
            write_section("Real volumes (--extra)", head[2:] + extra_rows)


def _cell(r: dict | None, limit: float, err: str) -> str:
    if r is None:
        return f"> {limit:.0f} s | – | –"
    if "missing" in r:
        return "not installed | – | –"
    return f"{r['seconds']:.2f} | {r['rss']:.2f} | {err}"


def solves(args: argparse.Namespace) -> None:
    from meshlap import _multigrid

    cubes = (12, 20) if args.quick else (20, 30, 40, 50)
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rows = []
    for n in cubes:
        spec = f"cube:{n}"
        for task in ("poisson", "heat"):
            res = {s: run(spec, f"{task}:{s}", args.limit) for s in ("auto", "direct", "lapy")}
            direct = res["direct"]
            cells = []
            for s in ("auto", "direct", "lapy"):
                r = res[s]
                if r is None or "missing" in r:
                    err = "–"
                elif task == "poisson":
                    err = f"{100 * r['err']:.3g}%"
                elif s == "lapy" or direct is None:
                    err = "–"
                else:
                    a, b = np.asarray(r["sample"]), np.asarray(direct["sample"])
                    err = f"{np.abs(a - b).max() / np.abs(b).max():.1e}"
                cells.append(_cell(r, args.limit, err))
            size = next((r["n"] for r in res.values() if r and "n" in r), 0)
            rows.append(f"| cube {n}³ | {size:,} | {task} | " + " | ".join(cells) + " |")
            print(rows[-1], flush=True)
    head = [f"Command: `python benchmarks/bench_volume_eigs.py --solves{' --quick' if args.quick else ''}"
            f" --limit {args.limit:g}` ({started}, 2 shared cores). `solver=\"auto\"` is conjugate "
            f"gradient with multigrid above {_multigrid.MAX_FACTOR_WORK:.0e} counted multiply-adds, SuperLU "
            "below. Seconds "
            "of the set-up and one solve (wall), peak resident GiB of its process; error: the Poisson "
            "solution's largest against the exact φ (relative), the heat step's largest difference "
            "from the direct step's (relative).", "",
            "| volume | vertices | task | auto s | GiB | error | direct s | GiB | error | LaPy s | GiB "
            "| error |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    if not args.no_write:
        write_section("Poisson solves and implicit heat steps (--solves)", head + rows)


if __name__ == "__main__":
    main()
