"""The derivation's modules form layers: the import graph of derive/toolconf_derive/ has no cycle,
and no module, script (derive/*.py) or check (derive/checks/) imports a toolconf_derive module
inside a function, where an import closes a loop unseen. Read from the source with `ast`, nothing
is imported.

    derive/.venv/bin/python -m unittest discover -s derive/tests      (part of make test)
"""

from __future__ import annotations

import ast
import functools
import unittest
from pathlib import Path

DERIVE = Path(__file__).resolve().parent.parent
PACKAGE = DERIVE / "toolconf_derive"
# The modules below the description readers: they import nothing of the package.
LEAVES = ("errors", "expression", "quantities", "progress")
# The layers as docs/explanation/pipeline.md draws them ("The derivation's modules"), top to bottom: a module imports only from
# the rows below its own.
LAYERS = (
    ("urdf_functions",),
    ("ir", "report", "urdf_model", "reference"),
    ("functions", "hoist", "sequence"),
    ("symbolic", "numeric", "rigid_body"),
    ("description",),
    ("urdf_description",),
    ("urdf",),
    ("files",),
    ("errors", "quantities", "expression", "exact", "planar_chain", "cost", "crosscheck", "ir_types", "rust_printer",
     "progress"),
)


@functools.cache
def package_modules() -> tuple[str, ...]:
    return tuple(sorted(p.stem for p in PACKAGE.glob("*.py") if p.stem != "__init__"))


def imported_modules(node: ast.AST, in_package: bool) -> list[str]:
    """The toolconf_derive modules an `import` or `from ... import` names: `from .x import y`
    (inside the package), `from toolconf_derive.x import y`, `from toolconf_derive import x` and
    `from . import x` (x a module), `import toolconf_derive.x`."""
    modules = set(package_modules())
    if isinstance(node, ast.Import):
        return [a.name.split(".")[1] for a in node.names
                if a.name.startswith("toolconf_derive.") and a.name.split(".")[1] in modules]
    if not isinstance(node, ast.ImportFrom):
        return []
    relative = node.level == 1 and in_package
    if relative or node.module == "toolconf_derive" or (node.module or "").startswith("toolconf_derive."):
        base = node.module if relative else (node.module or "").removeprefix("toolconf_derive").lstrip(".")
        if base:
            return [base.split(".")[0]] if base.split(".")[0] in modules else []
        return [a.name for a in node.names if a.name in modules]
    return []


def imports(path: Path, in_package: bool) -> list[tuple[str, bool, int]]:
    """(module, inside a function, line) for each toolconf_derive module `path` imports."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    found = []

    def visit(node: ast.AST, local: bool) -> None:
        for child in ast.iter_child_nodes(node):
            inner = local or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
            for module in imported_modules(child, in_package):
                found.append((module, local, child.lineno))
            visit(child, inner)

    visit(tree, False)
    return found


def package_graph() -> dict[str, set[str]]:
    """Each toolconf_derive module with the modules it imports, function-local imports included."""
    return {m: {i for i, _, _ in imports(PACKAGE / f"{m}.py", True)} for m in package_modules()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of `graph` as [a, b, ..., a], or None (depth-first search, nodes in name order)."""
    state: dict[str, str] = {}
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = "open"
        path.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                return path[path.index(nxt):] + [nxt]
            if nxt not in state and (cycle := visit(nxt)):
                return cycle
        state[node] = "done"
        path.pop()
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


class Layers(unittest.TestCase):
    def test_the_package_has_no_import_cycle(self):
        cycle = find_cycle(package_graph())
        self.assertIsNone(cycle, f"toolconf_derive imports in a circle: {' -> '.join(cycle or [])}")

    def test_no_function_local_import_of_the_package(self):
        files = [(p, True) for p in sorted(PACKAGE.glob("*.py"))]
        files += [(p, False) for p in sorted(DERIVE.glob("*.py")) + sorted((DERIVE / "checks").glob("*.py"))]
        local = [f"{p.relative_to(DERIVE)}:{line}: imports {m}"
                 for p, in_package in files for m, inside, line in imports(p, in_package) if inside]
        self.assertEqual(local, [], "import these at the top of the module (a lower layer never needs an upper one)")

    def test_the_leaves_import_nothing_of_the_package(self):
        graph = package_graph()
        for leaf in LEAVES:
            self.assertEqual(graph[leaf], set(), f"{leaf}.py is a leaf module")

    def test_each_module_imports_only_from_the_layers_below(self):
        row = {m: len(LAYERS) - i for i, layer in enumerate(LAYERS) for m in layer}
        self.assertEqual(sorted(row), sorted(package_modules()), "every module has one row in LAYERS")
        upward = [f"{m} -> {i}" for m, imported in package_graph().items() for i in sorted(imported)
                  if row[i] >= row[m]]
        self.assertEqual(upward, [], "an import from the same or a higher layer")

    def test_the_description_reader_is_below_the_urdf_rules(self):
        graph = package_graph()
        self.assertIn("urdf_description", graph["description"])
        self.assertIn("urdf", graph["urdf_description"])
        self.assertEqual(graph["urdf"], {"errors", "files"})

    def test_the_graph_is_read_as_written(self):
        # The parser against edges known by reading the files, so that a parser that finds
        # nothing cannot pass the tests above.
        graph = package_graph()
        self.assertEqual(graph["ir"] >= {"ir_types", "cost", "description", "functions", "symbolic"}, True, graph["ir"])
        scripts = {m for m, _, _ in imports(DERIVE / "derive.py", False)}
        self.assertTrue({"description", "functions", "ir", "symbolic", "urdf_functions"} <= scripts, scripts)

    def test_find_cycle_names_the_loop(self):
        self.assertEqual(find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}), ["a", "b", "c", "a"])
        self.assertEqual(find_cycle({"a": {"a"}}), ["a", "a"])
        self.assertIsNone(find_cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}))


if __name__ == "__main__":
    unittest.main()
