"""The ``meshlap`` command, run in-process through ``meshlap.cli.main``."""

import re
from pathlib import Path

import numpy as np
import pytest

import meshlap
from meshlap import io, reproduce
from meshlap.cli import build_parser, main

DATA = Path(__file__).parent / "data"
SPOT = str(DATA / "spot.obj")
SUBCOMMANDS = sorted(build_parser()._subparsers._group_actions[0].choices)


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def fails(capsys, expected, *argv, status=1):
    """Run the command; it must exit with ``status`` and end stderr with one error line."""
    code, _, err = run(capsys, *argv)
    assert code == status
    assert "Traceback" not in err
    last = err.strip().splitlines()[-1]
    assert last.startswith("meshlap") and "error:" in last and expected in last, err
    if status == 1:  # input errors: exactly one line; usage errors (2) print the usage first
        assert err.count("\n") == 1


def test_every_subcommand_has_help(capsys):
    assert set(SUBCOMMANDS) == {"info", "build", "eigs", "smooth", "curvature", "reproduce", "demo",
                                "distance"}
    code, out, _ = run(capsys, "--help")
    assert code == 0 and all(name in out for name in SUBCOMMANDS)
    for name in SUBCOMMANDS:
        code, out, _ = run(capsys, name, "--help")
        assert code == 0 and out.startswith(f"usage: meshlap {name}"), name
    code, out, _ = run(capsys, "--version")
    assert code == 0 and meshlap.__version__ in out


def test_usage_errors_exit_2(capsys):
    fails(capsys, "required", status=2)
    fails(capsys, "invalid choice", "frobnicate", status=2)
    fails(capsys, "expected a positive number", "build", SPOT, "--h", "-1", status=2)
    fails(capsys, "'abc'", "build", SPOT, "--h", "abc", status=2)
    fails(capsys, "positive integer", "demo", "--ns", "0", status=2)


def test_bad_input_exits_1_with_one_line(capsys, tmp_path):
    fails(capsys, "no such mesh file", "info", tmp_path / "nope.obj")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    fails(capsys, "bad.obj, line 4: face index 9 refers to no vertex", "build", bad)
    (tmp_path / "m.xyz").write_text("1 2 3\n")
    fails(capsys, "needs at least 4 distinct points", "info", tmp_path / "m.xyz")
    fails(capsys, "tol must lie in (0, 1)", "build", SPOT, "--tol", "3")
    np.savez(tmp_path / "other.npz", a=np.arange(3))
    fails(capsys, "not an operator saved by meshlap", "info", tmp_path / "other.npz")
    missing_dir = tmp_path / "no" / "such" / "dir" / "op.npz"
    fails(capsys, "No such file or directory", "build", SPOT, "--h", "0.001", "--correction", "none",
          "-o", missing_dir)


def test_a_reader_that_stops_early_is_no_error():
    """``meshlap info x | head -1``: the pipe closed before the output ends, quietly (141, as cat)."""
    import subprocess
    import sys

    p = subprocess.Popen([sys.executable, "-m", "meshlap.cli", "info", SPOT], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE)
    p.stdout.close()  # before meshlap writes a line
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) == 141
    assert err == ""


def test_info_mesh(capsys):
    code, out, _ = run(capsys, "info", SPOT)
    assert code == 0
    V, F = io.read_mesh(SPOT)
    table = [line for line in out.splitlines() if line and not line.startswith(("-", "2,"))]
    fields = dict(line.split(None, 1) for line in table)
    assert fields["vertices"] == "2,930" and fields["faces"] == "5,856 triangles"
    assert float(fields["h"].split()[0]) == pytest.approx(meshlap.default_h(V, F), rel=1e-5)
    assert float(fields["surface"].split()[-1]) == pytest.approx(meshlap.vertex_mass(V, F).sum(), rel=1e-5)
    assert "no problems found" in out
    # what meshlap.laplacian builds, and why; its pencil counted exactly (linear FEM is cheap)
    fields = dict(re.split(r"\s{2,}", line, maxsplit=1) for line in table)
    op = meshlap.laplacian(V, F)
    assert fields["operator"] == "fem pencil, fitted rows (op.decision)"
    assert fields["why"] == op.decision.reason
    assert fields["eigs solves"] == "quadratic elements (spectral.eigs)"
    assert fields["nnz of S"].startswith(f"{op.assemble().nnz:,} (7.0 per row)")
    code, out, _ = run(capsys, "info", DATA / "spot-quads.obj", "--h", "0.002")
    assert code == 0 and "2,928 quads" in out and "0.002" in out
    assert "kernel pencil, fitted rows" in out and "a kernel width h was given" in out and "nnz of S ≈" in out
    code, out, _ = run(capsys, "info", SPOT, "--correction", "none")  # the paper's operator, estimated
    assert code == 0 and "paper pencil, pencil rows" in out and "nnz of S ≈" in out



def test_info_mixed_polygons(capsys, tmp_path):
    p = tmp_path / "mixed.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4\nf 2 5 3\n")
    code, out, _ = run(capsys, "info", p)
    assert code == 0 and "1 triangles, 1 quads" in out and "1 boundary loop" in out


def test_build_then_info_of_the_operator(capsys, tmp_path):
    out_file = tmp_path / "spot.npz"
    code, out, err = run(capsys, "build", SPOT, "--h", "0.002", "--tol", "1e-6", "-o", out_file, "--progress")
    assert code == 0 and f"wrote {out_file}" in out
    assert "100%" in err  # the progress bar
    V, F = io.read_mesh(SPOT)
    ref = meshlap.laplacian(V, F, h=0.002, tol=1e-6)  # the CLI builds the library's default
    op = io.load_operator(out_file)
    assert abs(op.L - ref.L).max() == 0 and op.h == 0.002 and op.tol == 1e-6 and op.V is not None
    code, out, _ = run(capsys, "info", out_file)
    assert code == 0 and "0.002" in out and f"{ref.nnz:,}" in out and "mesh stored  yes" in out


def test_build_float32_without_mesh_default_name(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, _ = run(capsys, "build", SPOT, "--h", "0.001", "--float32", "--no-mesh")
    assert code == 0
    op = io.load_operator(tmp_path / "spot.npz")  # default: the mesh's name, in the current folder
    assert op.L.dtype == np.float32 and not hasattr(op, "V")


def test_demo_prints_falling_bsw_errors_beside_the_paper(capsys):
    code, out, _ = run(capsys, "demo", "--ns", "500", "2000")
    assert code == 0
    assert "uniform sphere" in out and "noisy sphere" in out and "absolute, as in the paper" in out
    rows = [line.split() for line in out.splitlines()]
    bsw = [r for r in rows if "BSW" in r[:2]]
    assert len(bsw) == 6 and all(r[-1] == "falling" for r in bsw)
    for r in bsw:  # n = 500 then n = 2,000: the error falls
        e500, e2000 = map(float, r[-3:-1])
        assert e2000 < e500
    # under every BSW and COT row: the paper's value and ours/paper, for all 24 published cells
    published = {(c.table, c.function, c.method, c.n): c.error for c in reproduce.paper_tables()}
    table, fn, seen = 3, None, 0
    for k, r in enumerate(rows):
        if r and r[0] == "noisy":
            table = 4
        if r and r[-1] in ("falling", "rising", "flat"):
            fn = r[0] if "BSW" == r[1] else fn
            method = r[-4]
            paper, ratio = rows[k + 1], rows[k + 2]
            assert paper[0] == "paper" and ratio[0] == "ours/paper"
            for n, ours, p, q in zip((500, 2000), map(float, r[-3:-1]), paper[1:], ratio[1:], strict=True):
                assert float(p) == published[(table, fn, method, n)]
                assert float(q) == pytest.approx(ours / float(p), rel=5e-3, abs=0.6e-4 / float(p))
                seen += 1
    assert seen == 24


def test_reproduce_writes_tables_and_png(capsys, tmp_path):
    out_dir = tmp_path / "tables"
    code, out, _ = run(capsys, "reproduce", "--quick", "--ns", "300", "500", "--out", out_dir)
    assert code == 0
    md = (out_dir / "tables.md").read_text()
    assert md.startswith("# Belkin–Sun–Wang") and "meshlap reproduce --quick --ns 300 500" in md
    assert "| x^2 | BSW |" in md and "| x^2 | COT |" in md
    # the paper beside ours at n = 500 (it has no n = 300): 26 published cells, each with its ratio
    assert md == out[: len(md)]
    paper = [line for line in md.splitlines() if "| paper |" in line]
    published = [c for c in reproduce.paper_tables() if c.n == 500]
    cells = [line.strip("|").split("|")[-1].strip() for line in paper]
    assert all(line.split("|")[4].strip() == "–" for line in paper)  # n = 300
    # Table 1's COT row stands under each of the three h
    assert len(cells) == len(published) + 2 * 2 and {float(c) for c in cells} == {c.error for c in published}
    assert (out_dir / "convergence.png").read_bytes()[:4] == b"\x89PNG"
    assert f"wrote {out_dir / 'convergence.png'}" in out


@pytest.fixture(scope="module")
def sphere_file(tmp_path_factory):
    V, F = meshlap.shapes.sphere(600, seed=0)
    return io.write_mesh(tmp_path_factory.mktemp("mesh") / "sphere.obj", V, F)


def eigen_table(out):
    rows = [line.split() for line in out.splitlines() if line.startswith(" ") and line.split()[0].isdigit()]
    return np.array([[float(v) for v in r[1:]] for r in rows])


def test_eigs_of_a_mesh_and_of_a_saved_operator(capsys, tmp_path, sphere_file):
    from meshlap.spectral import eigs, sphere_eigenvalue

    code, out, _ = run(capsys, "eigs", sphere_file, "-k", "9", "--h", "0.02", "--compare-cot",
                       "-o", tmp_path / "e.npz", "--png", tmp_path / "modes.png")
    assert code == 0 and "kernel, linear" in out and "COT" in out  # what was built and solved, by name
    table = eigen_table(out)
    V, F = io.read_mesh(sphere_file)
    lam, phi = eigs(meshlap.laplacian(V, F, h=0.02), 9)
    np.testing.assert_allclose(table[1:, 0], lam[1:], rtol=1e-5)
    # the unit sphere: degrees l = 1 (x3) and 2 (x5); COT approaches l(l+1), and so does the
    # default BSW (bias removed; measured within 0.9%), while the paper's operator (--correction
    # none) sits at the continuous operator's c_l(h) = 5.76 for l = 2 at h = 0.02
    degree = np.array([1, 1, 1, 2, 2, 2, 2, 2])
    assert table[0, 0] == 0 and table[0, 1] == 0
    np.testing.assert_allclose(table[1:, 1], degree * (degree + 1), rtol=0.02)
    np.testing.assert_allclose(table[1:, 0], degree * (degree + 1), rtol=0.012)
    code, out, _ = run(capsys, "eigs", sphere_file, "-k", "9", "--h", "0.02", "--correction", "none")
    plain = eigen_table(out)[1:, 0]
    np.testing.assert_allclose(plain, [sphere_eigenvalue(int(d), 0.02) for d in degree], rtol=0.02)
    saved = np.load(tmp_path / "e.npz")
    np.testing.assert_allclose(saved["eigenvalues"], lam, atol=1e-9)
    assert (tmp_path / "modes.png").read_bytes()[:4] == b"\x89PNG"
    # the same from the saved operator
    assert run(capsys, "build", sphere_file, "--h", "0.02", "-o", tmp_path / "op.npz")[0] == 0
    code, out, _ = run(capsys, "eigs", tmp_path / "op.npz", "-k", "9")
    assert code == 0 and "kernel, linear" in out  # the saved decision names the column
    np.testing.assert_allclose(eigen_table(out)[:, 0], table[:, 0], rtol=1e-5, atol=1e-12)
    code, out, _ = run(capsys, "eigs", sphere_file, "-k", "4")  # the default: FEM, quadratic elements
    assert code == 0 and "fem, quadratic" in out


def test_eigs_errors(capsys, tmp_path, sphere_file):
    assert run(capsys, "build", sphere_file, "--h", "0.02", "--no-mesh", "-o", tmp_path / "bare.npz")[0] == 0
    png, jpg = tmp_path / "x.png", tmp_path / "x.jpg"
    fails(capsys, "--png needs the mesh", "eigs", tmp_path / "bare.npz", "-k", "3", "--png", png)
    fails(capsys, "--png expects a file name ending in .png", "eigs", sphere_file, "--png", jpg)
    fails(capsys, "k must lie in", "eigs", sphere_file, "--h", "0.02", "-k", "600")


def test_smooth_makes_a_noisy_sphere_rounder(capsys, tmp_path):
    V, F = meshlap.shapes.sphere(1500, kind="noisy", seed=1)
    noisy = io.write_mesh(tmp_path / "noisy.off", V, F)

    def roughness(X):
        r = np.linalg.norm(X, axis=1)
        return r.std() / r.mean()

    def off_sphere(X):  # RMS distance to the clean unit sphere
        return np.sqrt(((np.linalg.norm(X, axis=1) - 1) ** 2).mean())

    # the plain flow (--h given): rounder, but shrunk
    h = str(float(meshlap.widths.default_h(V, F)) / 4)
    code, out, err = run(capsys, "smooth", noisy, "-o", tmp_path / "smooth.ply", "--h", h, "--steps", "2",
                         "--progress")
    assert code == 0 and "100%" in err and "enclosed volume" in out
    W, F2 = io.read_mesh(tmp_path / "smooth.ply")
    assert F2.shape == F.shape
    assert roughness(W) < 0.5 * roughness(V)
    # the library's denoising default: closer to the clean sphere than the input and than the
    # plain flow (noise of 0.05 mean edges: measured 0.00465 against 0.00486 and 0.021)
    code, out, _ = run(capsys, "smooth", noisy, "-o", tmp_path / "denoised.obj")
    assert code == 0 and "denoising" in out and "measured normal noise" in out
    D = io.read_mesh(tmp_path / "denoised.obj")[0]
    assert off_sphere(D) < 0.98 * off_sphere(V) and off_sphere(D) < 0.5 * off_sphere(W)
    code, _, _ = run(capsys, "smooth", noisy, "-o", tmp_path / "fixed.obj", "--fixed", "--cot")
    assert code == 0 and roughness(io.read_mesh(tmp_path / "fixed.obj")[0]) < roughness(V)
    fails(capsys, "--output must end in one of", "smooth", noisy, "-o", tmp_path / "out.xyz")


def test_curvature_of_a_sphere_of_radius_2(capsys, tmp_path):
    from meshlap.curvature import mean_curvature

    V, F = meshlap.shapes.sphere(2000, seed=0)
    path = io.write_mesh(tmp_path / "r2.obj", 2 * V, F)
    code, out, _ = run(capsys, "curvature", path, "--compare-cot", "-o", tmp_path / "H.npy",
                       "--png", tmp_path / "H.png")
    assert code == 0
    H = np.load(tmp_path / "H.npy")
    np.testing.assert_allclose(H, 0.5, atol=0.02)  # H = 1/R
    W, G = io.read_mesh(path)
    np.testing.assert_array_equal(H, mean_curvature(meshlap.laplacian(W, G), W, G))
    rows = {line.split()[0]: [float(v) for v in line.split()[1:]] for line in out.splitlines()
            if line.startswith(("BSW", "COT"))}
    assert abs(rows["BSW"][2] - 0.5) < 0.01 and abs(rows["COT"][2] - 0.5) < 0.01  # medians
    assert (tmp_path / "H.png").read_bytes()[:4] == b"\x89PNG"
    code, _, _ = run(capsys, "curvature", path, "-o", tmp_path / "H.csv")
    assert code == 0
    np.testing.assert_allclose(np.loadtxt(tmp_path / "H.csv"), H, rtol=1e-12)
    fails(capsys, "--output must end in .npy, .txt or .csv", "curvature", path, "-o", tmp_path / "H.bin")
