"""The tree's layering: import graph (function-level imports included), module and function
sizes, and a light CLI start."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("data_schemas", "gesture_db", "synth", "pipelines")
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 80


def project_modules(root: Path = ROOT) -> dict[str, Path]:
    """Dotted module name -> file, for every module of the four packages."""
    out = {}
    for pkg in PACKAGES:
        for path in sorted((root / pkg).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


def imported_modules(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """Project modules that ``name`` imports anywhere (module level or inside functions)."""
    is_package = path.name == "__init__.py"
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_package else name.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            for alias in node.names:
                sub = f"{module}.{alias.name}"
                found.add(sub if sub in known else module)
    return {m for m in found if m in known and m != name}


def import_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """Module -> the project modules it imports."""
    known = project_modules(root)
    return {n: imported_modules(n, p, known) for n, p in known.items()}


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return cycles


def is_numba_kernel(node: ast.FunctionDef) -> bool:
    """A function compiled by numba (``@njit``, ``@numba.jit``, ...)."""
    return any("njit" in ast.unparse(d) or "numba" in ast.unparse(d)
               for d in node.decorator_list)


def long_functions(limit: int = MAX_FUNCTION_LINES) -> list[str]:
    """Functions (not numba kernels) longer than ``limit`` lines, with their length."""
    out = []
    for name, path in project_modules().items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and not is_numba_kernel(
                    node):
                n = node.end_lineno - node.lineno + 1
                if n > limit:
                    out.append(f"{name}.{node.name}: {n} lines")
    return out


def kernels_outside_kernel_modules(root: Path = ROOT) -> list[str]:
    """Numba-compiled functions of the four packages in a module not named ``*_kernel``."""
    out = []
    for name, path in project_modules(root).items():
        if name.rsplit(".", 1)[-1].endswith("_kernel"):
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef) and is_numba_kernel(node):
                out.append(f"{name}.{node.name}")
    return out


def test_the_graph_finder_sees_a_cycle_through_a_function_level_import(tmp_path):
    pkg = tmp_path / "synth"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from synth.b import f\n")
    (pkg / "b.py").write_text("def f():\n    from synth import a\n    return a\n")
    for other in PACKAGES[:2] + PACKAGES[3:]:
        (tmp_path / other).mkdir()
    graph = import_graph(tmp_path)
    assert graph["synth.b"] == {"synth.a"}
    assert import_cycles(graph) == [["synth.a", "synth.b"]]


def test_no_import_cycles_even_through_imports_inside_functions():
    assert import_cycles(import_graph()) == []


def test_layers_data_schemas_imports_none_of_ours_and_gesture_db_and_synth_are_apart():
    graph = import_graph()
    bad = []
    for module, deps in graph.items():
        top = module.split(".")[0]
        for dep in deps:
            other = dep.split(".")[0]
            if top == "data_schemas" and other != "data_schemas":
                bad.append(f"{module} -> {dep}")
            if {top, other} == {"synth", "gesture_db"}:
                bad.append(f"{module} -> {dep}")
    assert bad == []


def test_no_module_over_500_lines():
    sizes = {n: len(p.read_text(encoding="utf-8").splitlines())
             for n, p in project_modules().items()}
    assert {n: k for n, k in sizes.items() if k > MAX_MODULE_LINES} == {}


def test_no_function_over_80_lines_outside_numba_kernels():
    assert long_functions() == []


def test_the_kernel_finder_sees_a_numba_function_outside_a_kernel_module(tmp_path):
    for pkg in PACKAGES:
        (tmp_path / pkg).mkdir()
    (tmp_path / "synth" / "fast_kernel.py").write_text(
        "@njit(cache=True)\ndef a(x):\n    return x\n")
    (tmp_path / "synth" / "slow.py").write_text(
        "import numba\n\n\nclass C:\n    @staticmethod\n    @numba.njit\n    def b(x):\n"
        "        return x\n\n\ndef c(x):\n    return x\n")
    assert kernels_outside_kernel_modules(tmp_path) == ["synth.slow.b"]


def test_every_numba_function_lives_in_a_kernel_module():
    assert kernels_outside_kernel_modules() == []


def command_paths(parser=None, prefix=()) -> list[tuple[str, ...]]:
    """Every sub-command of ``arco`` (nested ones such as ``db info`` included)."""
    import argparse

    from pipelines.cli.main import build_parser

    parser = parser or build_parser()
    out = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                out.append((*prefix, name))
                out.extend(command_paths(sub, (*prefix, name)))
    return out


@pytest.mark.parametrize("argv", [["--help"], ["--version"]]
                         + [[*path, "--help"] for path in command_paths()], ids=" ".join)
def test_help_imports_no_heavy_library(argv):
    """``arco --help`` and every ``arco COMMAND --help`` start fast: nothing numeric is
    imported to print them."""
    code = ("import sys\nfrom pipelines.cli.main import main\n"
            f"try:\n    main({argv!r})\nexcept SystemExit:\n    pass\n"
            "heavy = sorted(m for m in ('numpy', 'pandas', 'pyarrow', 'scipy', 'numba', "
            "'sklearn', 'music21', 'librosa', 'matplotlib', 'dask') if m in sys.modules)\n"
            "print('HEAVY', heavy)\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, timeout=60)
    assert "HEAVY []" in run.stdout, run.stdout + run.stderr
