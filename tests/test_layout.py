"""The layout of the package: a package imports only the packages below it, no two modules
import each other (directly or through others, deferred imports and type-only imports
included), no module imports another's private names, at most eight modules stand at the root,
and a package's ``__init__.py`` holds only its docstring and re-exports.  Checked on the source
(its syntax trees), so the rules hold for code no test runs."""
from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "mutrose_cp"
# lowest first: a package may import only those before it (and itself)
LAYERS = ["errors", "interrupt", "lazy_exports", "model", "io", "pipeline", "solve", "output", "allocate", "validate", "compare",
          "mission", "api", "cli", "__main__"]


def _module(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module(p): p for p in PACKAGE.rglob("*.py")}


def _imports(name: str) -> list[tuple[str, list[str], int]]:
    """(imported module, names, line) of every ``from ... import`` of the package in a module."""
    path = MODULES[name]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else [])) if node.level else node.module or ""
            if module.split(".")[0] == "mutrose_cp":
                found.append((module, [a.name for a in node.names], node.lineno))
        elif isinstance(node, ast.Import):
            found += [(a.name, [], node.lineno) for a in node.names if a.name.split(".")[0] == "mutrose_cp"]
    return found


def _graph() -> nx.DiGraph:
    graph = nx.DiGraph()
    for name in MODULES:
        graph.add_node(name)
        for module, names, line in _imports(name):
            targets = [f"{module}.{n}" for n in names if f"{module}.{n}" in MODULES] or [module]
            for target in targets:
                if target != name:
                    graph.add_edge(name, target, line=line)
    return graph


def _layer(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def test_no_module_imports_itself_through_others():
    graph = _graph()
    # a package's __init__ re-exporting its modules is not a cycle of theirs
    cycles = [c for c in nx.simple_cycles(graph.subgraph(n for n in graph if MODULES[n].name != "__init__.py"))]
    assert not cycles, "\n".join(" -> ".join(c + [c[0]]) for c in sorted(cycles)[:20])


def test_packages_import_only_the_packages_below_them():
    rank = {layer: i for i, layer in enumerate(LAYERS)}
    upward = []
    for source, target, data in _graph().edges(data=True):
        a, b = _layer(source), _layer(target)
        if a != b and b != "__init__" and rank.get(b, len(rank)) > rank.get(a, len(rank)):
            upward.append(f"{MODULES[source].relative_to(PACKAGE.parent)}:{data['line']}: {source} imports {target}")
    assert not upward, "\n".join(sorted(upward))


def test_no_private_name_is_imported_from_another_module():
    private = [f"{MODULES[name].relative_to(PACKAGE.parent)}:{line}: {n} from {module}"
               for name in MODULES for module, names, line in _imports(name)
               for n in names if n.startswith("_") and not n.startswith("__")]
    assert not private, "\n".join(private)


def test_at_most_eight_modules_stand_at_the_root():
    root = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(root) <= 8, root


def test_package_faces_hold_only_a_docstring_and_re_exports():
    logic = []
    for path in PACKAGE.rglob("__init__.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for i, node in enumerate(tree.body):
            docstring = i == 0 and isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
            exports = isinstance(node, ast.Assign) and [getattr(t, "id", "") for t in node.targets] in (
                ["__all__"], ["__version__"])
            # a lazy face (PEP 562): its table of exports and the __getattr__ that loads them
            lazy = isinstance(node, ast.Assign) and [getattr(t, "id", "") for t in node.targets] in (
                ["_EXPORTS"], ["__getattr__"])
            if not (docstring or exports or lazy or isinstance(node, (ast.Import, ast.ImportFrom))
                    or (isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING")):
                logic.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {type(node).__name__}")
    assert not logic, "\n".join(logic)
