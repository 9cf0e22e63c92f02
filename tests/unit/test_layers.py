"""The package's layers (docs/developer/architecture.md): every import
between petthm's modules, those inside functions included, goes from a
layer to the same or a lower one, and no import cycle exists.  The
negative controls plant a cycle and an upward import in a copy of the
package."""
import ast
import os
import shutil

import pytest

from conftest import ROOT, read_text

#: the layers, bottom up; a module's layer is its subpackage's (top-level modules: the base)
LAYERS = ("base", "mesh", "discretisation", "physics", "solvers", "io", "scenes", "run", "cli")
PACKAGE_LAYER = {"mesh": "mesh", "discretisation": "discretisation", "physics": "physics",
                 "verification": "physics", "solvers": "solvers", "io": "io", "scenes": "scenes",
                 "run": "run"}
#: modules at the top of the package besides __init__ and __main__ (the base layer)
MAX_TOP_LEVEL = 12


def modules(root: str) -> dict[str, str]:
    out = {}
    for d, _, files in os.walk(os.path.join(root, "petthm")):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(d, f)
                name = os.path.relpath(path, root)[:-3].replace(os.sep, ".")
                out[name[:-9] if name.endswith(".__init__") else name] = path
    return out


def layer(name: str) -> int:
    parts = name.split(".")
    if parts[1:] == ["__main__"]:
        return LAYERS.index("cli")
    if len(parts) > 2 or (len(parts) == 2 and parts[1] in PACKAGE_LAYER):
        return LAYERS.index(PACKAGE_LAYER[parts[1]])
    return LAYERS.index("base")


def imports(root: str) -> dict[str, set[str]]:
    """{module: the petthm modules it imports} (every import statement, at any depth)."""
    mods = modules(root)
    graph = {}
    for name, path in mods.items():
        package = name if path.endswith("__init__.py") else name.rsplit(".", 1)[0]
        found = set()
        for node in ast.walk(ast.parse(read_text(path))):
            if isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parts = package.split(".")[:len(package.split(".")) - node.level + 1]
                    base = ".".join(parts + ([node.module] if node.module else []))
                if base != "petthm" and not base.startswith("petthm."):
                    continue
                for a in node.names:
                    found.add(f"{base}.{a.name}" if f"{base}.{a.name}" in mods else base)
            elif isinstance(node, ast.Import):
                found |= {a.name for a in node.names if a.name in mods}
        graph[name] = {m for m in found if m in mods and m != name}
    return graph


def cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle, or None (depth-first search)."""
    state, stack = {}, []

    def visit(v):
        state[v] = 1
        stack.append(v)
        for w in sorted(graph[v]):
            if state.get(w) == 1:
                return stack[stack.index(w):] + [w]
            if w not in state and (found := visit(w)):
                return found
        stack.pop()
        state[v] = 2
        return None
    for v in sorted(graph):
        if v not in state and (found := visit(v)):
            return found
    return None


def upward(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """Imports from a lower layer to a higher one (a package's __init__ may
    import what it exports from its own package)."""
    return sorted((a, b) for a, targets in graph.items() for b in targets if layer(b) > layer(a))


def check(root: str) -> list[str]:
    graph = imports(root)
    problems = [f"{a} imports {b} (layer {LAYERS[layer(a)]} < {LAYERS[layer(b)]})" for a, b in upward(graph)]
    found = cycle(graph)
    if found:
        problems.append("import cycle: " + " -> ".join(found))
    return problems


def test_the_layers_hold_and_no_import_cycle_exists():
    assert check(ROOT) == []


def test_at_most_twelve_modules_at_the_top_of_the_package():
    top = [f for f in os.listdir(os.path.join(ROOT, "petthm"))
           if f.endswith(".py") and f not in ("__init__.py", "__main__.py")]
    assert len(top) <= MAX_TOP_LEVEL, top


@pytest.mark.parametrize("plant", ["cycle", "upward"])
def test_the_check_finds_a_planted_cycle_or_upward_import(tmp_path, plant):
    """Negative controls on a copy of the package."""
    shutil.copytree(os.path.join(ROOT, "petthm"), tmp_path / "petthm")
    if plant == "cycle":          # errors imports params, which imports errors
        with open(tmp_path / "petthm" / "errors.py", "a") as f:
            f.write("\n\ndef _planted():\n    from petthm import params  # noqa: F401\n")
    else:                         # the mesh layer imports the run driver
        with open(tmp_path / "petthm" / "mesh" / "plex.py", "a") as f:
            f.write("\n\ndef _planted():\n    from petthm.run import driver  # noqa: F401\n")
    problems = check(str(tmp_path))
    assert problems and any(("cycle" if plant == "cycle" else "imports petthm.run.driver") in p
                            for p in problems), problems
