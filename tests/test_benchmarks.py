"""The scripts of benchmarks/ parse their options (``--help`` prints them and does not run the
benchmark: several had none, and ``--help`` ran them, some writing RESULTS.md), and call only
what meshlap has."""

from __future__ import annotations

import ast
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def test_every_script_parses_its_options() -> None:
    missing = []
    for path in sorted(BENCHMARKS.glob("*.py")):
        text = path.read_text(encoding="utf-8")
        runs = any(isinstance(node, ast.If) and "__main__" in ast.unparse(node.test)
                   for node in ast.parse(text).body)
        if runs and "ArgumentParser" not in text:
            missing.append(path.name)
    assert not missing, f"scripts without an argument parser: {missing}"


def _meshlap_names(tree: ast.Module) -> dict[str, tuple[str, str | None]]:
    """The names a script binds to meshlap: name → (module, attribute or None)."""
    bound: dict[str, tuple[str, str | None]] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "meshlap":
                    bound[alias.asname or "meshlap"] = (alias.name if alias.asname else "meshlap", None)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module.split(".")[0] == "meshlap":
            for alias in node.names:
                bound[alias.asname or alias.name] = (node.module, alias.name)
    return bound


def _chain(node: ast.Attribute) -> list[str] | None:
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    return [node.id, *parts[::-1]] if isinstance(node, ast.Name) else None


def test_every_meshlap_name_a_script_uses_exists() -> None:
    """A benchmark calls only what meshlap has: bench_eigs.py called ``spectral._one_blas_thread``
    for weeks after it moved, and its RESULTS section went stale. Attribute chains on the names a
    script imports from meshlap are resolved here, without running the script (names it rebinds
    locally are left out)."""
    import importlib
    import types

    def resolve(obj: object, name: str) -> object:
        if hasattr(obj, name):
            return getattr(obj, name)
        if isinstance(obj, types.ModuleType):  # a submodule not imported by its package
            return importlib.import_module(f"{obj.__name__}.{name}")
        raise AttributeError(name)

    missing = []
    for path in sorted(BENCHMARKS.glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        stored = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
        roots = {}
        for name, (module, attr) in _meshlap_names(tree).items():
            try:
                root = importlib.import_module(module)
                roots[name] = root if attr is None else resolve(root, attr)
            except (ImportError, AttributeError) as exc:
                if "mpi4py" in str(exc) or "petsc4py" in str(exc):  # the optional MPI extra
                    continue
                missing.append(f"{path.name}: from {module} import {attr} ({exc})")
        inner = {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
        for node in ast.walk(tree):
            if not isinstance(node, ast.Attribute) or id(node) in inner:
                continue
            chain = _chain(node)
            if not chain or chain[0] not in roots or chain[0] in stored:
                continue
            obj = roots[chain[0]]
            for i, part in enumerate(chain[1:], 1):
                try:
                    obj = resolve(obj, part)
                except (ImportError, AttributeError):
                    missing.append(f"{path.name}:{node.lineno}: {'.'.join(chain[:i + 1])}")
                    break
    assert not missing, "benchmarks use names meshlap does not have:\n" + "\n".join(missing)


def test_the_smoke_run_knows_every_script() -> None:
    """benchmarks/smoke.py runs each script once at a small size; a new script is added there."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("smoke", BENCHMARKS / "smoke.py")
    smoke = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(smoke)
    scripts = {p.name for p in BENCHMARKS.glob("*.py")}
    assert scripts - set(smoke.RUNS) - smoke.NOT_RUN == set(), "scripts smoke.py does not run"
    assert set(smoke.RUNS) | smoke.NOT_RUN <= scripts, "smoke.py names scripts that are gone"
    assert smoke.CORPUS <= set(smoke.RUNS)
