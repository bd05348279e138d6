"""Every script in examples/ runs to the end (each asserts its own results against ground
truth) and prints or writes what it promises."""

import runpy
import sys
from pathlib import Path

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
SCRIPTS = sorted(p.name for p in EXAMPLES.glob("*.py"))


def run_example(name, args, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", [str(EXAMPLES / name), *map(str, args)])
    runpy.run_path(str(EXAMPLES / name), run_name="__main__")
    return capsys.readouterr().out


def test_every_example_is_tested():
    # distributed_job.py runs under mpiexec in tests/test_distributed.py
    assert set(SCRIPTS) == {"conventions.py", "eigenfunctions.py", "noisy_sphere.py", "quickstart.py",
                            "save_and_reload.py", "distributed_job.py"}


def test_quickstart(monkeypatch, capsys, tmp_path):
    monkeypatch.chdir(tmp_path)
    out = run_example("quickstart.py", [], monkeypatch, capsys)
    assert "spot.obj: 2,930 vertices, 5,856 faces" in out
    lines = [line.strip() for line in out.splitlines()]
    energies = [float(line.split()[-1]) for line in lines if line.startswith(("COT", "BSW h"))]
    cot, bsw = energies[0], energies[1:]
    # the heat-kernel energy approaches the cotangent one as h shrinks
    gaps = [abs(e / cot - 1) for e in bsw]
    assert gaps == sorted(gaps, reverse=True) and gaps[-1] < 0.02


def test_conventions(monkeypatch, capsys):
    out = run_example("conventions.py", [], monkeypatch, capsys)
    rows = ("meshlap  S", "libigl   C", "robust   L")
    signs = [line.split(":")[-1].strip() for line in out.splitlines() if line.strip().startswith(rows)]
    assert [s[0] for s in signs] == ["-", "-", "+"]
    assert "(M-orthonormal)" in out and "(not orthonormal)" in out


def test_save_and_reload(monkeypatch, capsys, tmp_path):
    out = run_example("save_and_reload.py", [tmp_path / "out"], monkeypatch, capsys)
    assert (tmp_path / "out" / "spot-quads.npz").is_file() and (tmp_path / "out" / "sphere.ply").is_file()
    assert "bit-for-bit" in out and "max |L - op.L| = 0.0" in out


def test_eigenfunctions(monkeypatch, capsys, tmp_path):
    out = run_example("eigenfunctions.py", [tmp_path], monkeypatch, capsys)
    assert (tmp_path / "spot_eigenfunctions.png").read_bytes()[:4] == b"\x89PNG"
    rows = [line.split() for line in out.splitlines() if line[:2].strip().isdigit()]
    assert len(rows) == 8 and [float(v) for v in rows[0][1:]] == [0.0, 0.0, 0.0]
    wide, narrow, cot = (np.array([float(r[c]) for r in rows]) for c in (1, 2, 3))
    assert np.all(np.diff(wide) >= 0) and np.all(np.diff(cot) >= 0)
    assert abs(narrow[1] / cot[1] - 1) < 0.05


def test_noisy_sphere(monkeypatch, capsys, tmp_path):
    out = run_example("noisy_sphere.py", [tmp_path], monkeypatch, capsys)
    png = tmp_path / "noisy_sphere.png"
    assert png.read_bytes()[:4] == b"\x89PNG"
    rows = [line.split() for line in out.splitlines() if line[:1].isdigit()]
    bsw, cot = [float(r[1]) for r in rows], [float(r[2]) for r in rows]
    assert bsw == sorted(bsw, reverse=True) and bsw[-1] < cot[-1]


def test_conventions_block_runs(capsys):
    guide = (ROOT / "docs" / "operator.md").read_text(encoding="utf-8")
    section = guide.split("\n## Conventions\n", 1)[1].split("\n## ", 1)[0]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    exec(compile(code, "docs/operator.md (Conventions)", "exec"), {})
    errors = [float(v) for v in capsys.readouterr().out.split()]
    assert len(errors) == 3 and max(errors) < 5e-3


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    import matplotlib.pyplot as plt

    plt.close("all")
