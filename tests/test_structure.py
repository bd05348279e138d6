"""The layout shows the pipeline: no import cycle, short modules, each stage computed once."""

import ast
from pathlib import Path

import numpy as np
import pytest

import meshlap
from meshlap import samples, shapes
from meshlap.geometry import frames

PACKAGE = Path(meshlap.__file__).parent
MAX_LINES = 600


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path) -> set[str]:
    """Every meshlap module this file imports, at any depth of the file (deferred imports
    count too), with the packages Python runs on the way (not those enclosing the file)."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        targets: list[str] = []
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            targets = [mod] + [f"{mod}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        for t in targets:
            parts = t.split(".")
            for i in range(2, len(parts) + 1):  # the packages on the way, then the module
                out.add(".".join(parts[:i]))
    modules = {_module_name(p) for p in PACKAGE.rglob("*.py")}
    # a module's own enclosing packages are already running when it runs: not an edge
    own = {".".join(name.split(".")[:i]) for i in range(1, name.count(".") + 1)}
    return {m for m in out if m in modules and m != name and m not in own}


def test_no_import_cycle():
    graph = {_module_name(p): _imports(p) for p in PACKAGE.rglob("*.py")}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for n in sorted(graph.get(m, ())):
            if state.get(n) == 1:
                cycle = stack[stack.index(n):] + [n]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m)


def test_cycle_detector_sees_a_cycle(tmp_path, monkeypatch):
    # the detector itself: two modules that import each other are reported
    pkg = tmp_path / "meshlap"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from . import b\n")
    (pkg / "b.py").write_text("def f():\n    from .a import x\n")
    monkeypatch.setitem(globals(), "PACKAGE", pkg)
    with pytest.raises(pytest.fail.Exception, match="import cycle"):
        test_no_import_cycle()


def test_modules_are_short():
    long = {str(p.relative_to(PACKAGE)): n for p in PACKAGE.rglob("*.py")
            if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_stages_live_in_their_modules():
    for name in ("geometry", "widths", "assembly", "corrections", "pipeline", "operator", "distributed"):
        assert (PACKAGE / name).exists() or (PACKAGE / f"{name}.py").exists()


def test_tuned_constants_are_in_one_place_each_documented_and_used():
    # meshlap.tuned holds the builders' tuned constants: each with its line of provenance (a "#:"
    # comment right above it), each in __all__, and each imported by a module of meshlap (ruff's
    # unused-import check then sees that the module uses it)
    path = PACKAGE / "tuned.py"
    lines = path.read_text().splitlines()
    names = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Assign) and node.targets[0].id != "__all__":
            name = node.targets[0].id
            names.add(name)
            doc = lines[node.lineno - 2]
            assert doc.startswith("#: ") and len(doc) > 40, f"{name}: no line of provenance above it"
    assert names == set(meshlap.tuned.__all__) and len(names) > 30
    imported = set()
    for p in PACKAGE.rglob("*.py"):
        if p == path:
            continue
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module == "tuned" and node.level:
                imported |= {a.name for a in node.names}
    assert names - imported == set(), f"tuned constants no module uses: {sorted(names - imported)}"


def _counting(monkeypatch, module, name, calls):
    original = getattr(module, name)

    def counted(*args, **kwargs):
        calls[name] = calls.get(name, 0) + 1
        return original(*args, **kwargs)

    monkeypatch.setattr(module, name, counted)


@pytest.mark.parametrize("kind", ["plane", "cloud", "tets"])
def test_frames_computed_once_per_build(monkeypatch, kind):
    """Normals, tangent frames and the boundary: one computation each, whatever the stages
    that read them (widths, arc distances, mirror images, the moment scale)."""
    calls: dict[str, int] = {}
    for name in ("vertex_normals", "pca_frames", "boundary_samples_surface", "boundary_samples_cloud",
                 "boundary_samples_volume", "orient_normals"):
        _counting(monkeypatch, frames, name, calls)
    if kind == "plane":
        V, F = shapes.plane(1500, seed=0)
        op = meshlap.laplacian(V, F, operator="kernel")
        expect = {"vertex_normals": 1, "boundary_samples_surface": 1}
    elif kind == "cloud":
        rng = np.random.default_rng(0)
        P = np.column_stack([rng.uniform(-1, 1, (3000, 2)), np.zeros(3000)])
        op = meshlap.point_cloud_laplacian(P, operator="kernel")
        expect = {"pca_frames": 1, "orient_normals": 1, "boundary_samples_cloud": 1}
    else:
        V, T = samples.cube_tetrahedra(6)
        op = meshlap.laplacian(V, T, k=3, operator="kernel")
        expect = {"boundary_samples_volume": 1}
    assert op.correction == "richardson" and op.boundary_rows > 0
    assert calls == expect
