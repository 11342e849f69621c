"""The package's shape: data flows one way, the engine imports nothing above it, and the
guide's table of outputs (docs/guide.md) is the registry's."""

from __future__ import annotations

import ast
from pathlib import Path

from harvester_sweep import outputs

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "harvester_sweep"
BEGIN = "<!-- metrics table: generated from harvester_sweep/outputs.py, do not edit by hand -->"
END = "<!-- end of metrics table -->"


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    """Modules of harvester_sweep that ``path`` imports, anywhere in the file."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{base}.{node.module}" if node.module else base
            else:
                base = node.module or ""
            if base.startswith("harvester_sweep"):
                found.add(base)
                # "from . import x" imports the module x
                found.update(f"{base}.{a.name}" for a in node.names
                             if (PACKAGE.parent / f"{base}.{a.name}".replace(".", "/")).with_suffix(
                                 ".py").exists())
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("harvester_sweep"))
    return found - {name}


def _graph() -> dict[str, set[str]]:
    modules = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    return {name: _imports(path) & set(modules) for name, path in modules.items()}


def test_the_engine_imports_nothing_from_the_layers_above_it():
    for path in (PACKAGE / "_engine").glob("*.py"):
        outside = {m for m in _imports(path) if not m.startswith("harvester_sweep._engine")}
        assert not outside, f"{path.name} imports {outside}"
        tree = ast.parse(path.read_text())
        third_party = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import)
                       for a in n.names}
        third_party |= {n.module.split(".")[0] for n in ast.walk(tree)
                        if isinstance(n, ast.ImportFrom) and not n.level}
        assert third_party <= {"numba", "numpy", "math", "threading", "hashlib", "pathlib",
                               "collections", "__future__"}, (path.name, third_party)


def test_no_module_imports_itself_through_others():
    graph = _graph()
    # the package's __init__ re-exports the API; it is the top, not a layer
    graph = {m: {d for d in deps if d != "harvester_sweep"} for m, deps in graph.items()}
    state: dict[str, int] = {}

    def visit(module, path):
        if state.get(module) == 1:
            raise AssertionError("import cycle: " + " -> ".join(path + [module]))
        if state.get(module) == 2:
            return
        state[module] = 1
        for dep in sorted(graph[module]):
            # a subpackage's __init__ importing its own modules is no cycle
            if not (module.endswith("_engine") and dep.startswith(module)):
                visit(dep, path + [module])
        state[module] = 2

    for module in sorted(graph):
        visit(module, [])


def test_the_guides_table_of_outputs_is_the_registrys():
    guide = (ROOT / "docs" / "guide.md").read_text()
    table = guide[guide.index(BEGIN) + len(BEGIN):guide.index(END)].strip()
    assert table == outputs.markdown_table(), (
        "docs/guide.md's table of outputs is out of date: paste "
        "`python -m harvester_sweep.outputs`")


def test_every_status_has_a_cf_flag_and_every_output_cf_attributes():
    flags = outputs.STATUS_FLAGS
    assert list(flags["flag_values"]) == [s.code for s in outputs.STATUSES]
    assert flags["flag_meanings"].split() == [s.name.replace(" ", "_") for s in outputs.STATUSES]
    for output in outputs.OUTPUTS.values():
        assert output.attrs["units"] and output.attrs["long_name"], output.name
