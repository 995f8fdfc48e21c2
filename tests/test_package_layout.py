"""The package's layout rules: small modules, no private name crossing a module boundary,
no import cycle, no citation of a file that is not in the repository, and no solver library
imported with the package."""

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "barrierjax"
MODULES = sorted(PACKAGE.rglob("*.py"))
# Private modules of the package, imported whole (as diffrax does with its `_custom_types`).
PRIVATE_MODULES = {"_checks", "_custom_types", "_solve", "_xla_flags"}


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path):
    """(module imported, names) for each intra-package `from ... import ...`, resolved to
    absolute module names."""
    package = module_name(path).split(".")
    if path.name != "__init__.py":
        package = package[:-1]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level:
            base = package[: len(package) - node.level + 1]
            module = ".".join(base + ([node.module] if node.module else []))
            yield module, [alias.name for alias in node.names]


def test_modules_have_at_most_600_lines():
    sizes = {str(p.relative_to(PACKAGE)): len(p.read_text().splitlines()) for p in MODULES}
    assert {name: n for name, n in sizes.items() if n > 600} == {}


def test_no_private_name_is_imported_from_another_module():
    crossing = [
        f"{module_name(path)}: {module}.{name}"
        for path in MODULES
        for module, names in imports(path)
        for name in names
        if name.startswith("_") and name not in PRIVATE_MODULES
    ]
    assert crossing == []


def test_no_import_cycle():
    known = {module_name(p) for p in MODULES}
    graph = {module_name(p): set() for p in MODULES}
    for path in MODULES:
        for module, names in imports(path):
            # `from . import x` imports the submodule x when there is one.
            targets = {f"{module}.{n}" for n in names if f"{module}.{n}" in known}
            targets = targets or ({module} if module in known else set())
            graph[module_name(path)] |= targets - {module_name(path)}
    # A package imports its submodules through its __init__; a submodule importing its
    # own package's __init__ is the usual re-export, not a cycle of concern.
    for name in graph:
        graph[name] = {t for t in graph[name] if not name.startswith(t + ".")}

    state: dict[str, int] = {}

    def visit(node, path):
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                pytest.fail("import cycle: " + " -> ".join(path[path.index(nxt) :] + [nxt]))
            if nxt not in state:
                visit(nxt, path + [nxt])
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])


@pytest.mark.parametrize("pattern", [r"ERRATA\.md", r"DESIGN\.md", r"\.\./shared"])
def test_no_citation_of_files_outside_the_repository(pattern):
    root = PACKAGE.parent
    texts = [*MODULES, *root.glob("*.md"), *(root / "docs").rglob("*.md")]
    texts += [*(root / "benchmarks").glob("*.py"), *(root / "tests").glob("*.py")]
    texts += [*PACKAGE.rglob("*.toml"), root / "benchmarks" / "README.md"]
    hits = [
        str(p.relative_to(root))
        for p in texts
        if p != Path(__file__).resolve() and re.search(pattern, p.read_text())
    ]
    assert hits == []


def test_the_package_and_its_command_line_import_no_solver_library():
    # diffrax, optimistix, lineax and optax are imported where a solve is traced
    # (`_solve.phases`): a second run of the command line, which loads its compiled
    # programs, never needs them (about 0.35 s of its 3 s on 2 cores).
    code = "import sys, barrierjax, barrierjax.cli; print(*sys.modules, sep='\\n')"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    ).stdout
    loaded = {name.split(".")[0] for name in out.split()}
    assert loaded & {"diffrax", "optimistix", "lineax", "optax"} == set()
