"""The package's shape: data flows one way, the engine imports nothing above it, and the
guide's table of outputs (docs/guide.md) is the registry's."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from harvester_sweep import outputs

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "harvester_sweep"
BEGIN = "<!-- metrics table: generated from harvester_sweep/outputs.py, do not edit by hand -->"
END = "<!-- end of metrics table -->"


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _is_module(name: str) -> bool:
    path = PACKAGE.parent / name.replace(".", "/")
    return path.with_suffix(".py").exists() or (path / "__init__.py").exists()


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
                # "from . import x" imports the module x; any other name comes from base
                modules = {f"{base}.{a.name}" for a in node.names if _is_module(f"{base}.{a.name}")}
                found.update(modules)
                if len(modules) < len(node.names):
                    found.add(base)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("harvester_sweep"))
    return found - {name}


def _graph() -> dict[str, set[str]]:
    modules = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    return {name: _imports(path) & set(modules) for name, path in modules.items()}


# What the compiled layers may import from the package: the engine its own modules, the
# models it runs and the compile flags; a model other models' parts and the flags.
COMPILED = {"_engine": ("harvester_sweep._engine", "harvester_sweep.models", "harvester_sweep.jit"),
            "models": ("harvester_sweep.models", "harvester_sweep.jit")}


@pytest.mark.parametrize("folder", sorted(COMPILED))
def test_the_engine_and_the_models_import_nothing_from_the_layers_above_them(folder):
    for path in (PACKAGE / folder).glob("*.py"):
        outside = {m for m in _imports(path) if not m.startswith(COMPILED[folder])}
        assert not outside, f"{path.name} imports {outside}"
        tree = ast.parse(path.read_text())
        third_party = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import)
                       for a in n.names}
        third_party |= {n.module.split(".")[0] for n in ast.walk(tree)
                        if isinstance(n, ast.ImportFrom) and not n.level}
        standard = {"math", "threading", "concurrent", "hashlib", "pathlib", "collections", "os",
                    "pickle", "__future__"}
        assert third_party <= {"numba", "numpy"} | standard, (path.name, third_party)


def test_no_module_imports_itself_through_others():
    graph = _graph()
    state: dict[str, int] = {}

    def visit(module, path):
        if state.get(module) == 1:
            raise AssertionError("import cycle: " + " -> ".join(path + [module]))
        if state.get(module) == 2:
            return
        state[module] = 1
        for dep in sorted(graph[module]):
            # a subpackage's __init__ importing its own modules is no cycle (the package's
            # own __init__ is no subpackage's)
            if not (module != "harvester_sweep" and dep.startswith(module + ".")):
                visit(dep, path + [module])
        state[module] = 2

    for module in sorted(graph):
        visit(module, [])


# The package's layers, lowest first: a module imports from its own layer or those below,
# never from one above (the package's __init__, which re-exports the API, is the top).
LAYERS = (
    ("version", "jit", "environment"),
    ("models",),
    ("_engine",),
    ("contact", "materials", "linear", "bimorph", "rod", "dense"),
    ("timescales",),
    ("parameters", "beam_parameters"),
    ("outputs", "packing"),
    ("period_map", "accuracy", "acceptance", "modal_map", "beam_packing"),
    ("orbits",),
    ("results", "run_estimate"),
    ("datasets", "plots"),
    ("scene", "continuation", "basins", "sweep_file", "chunks", "chunk_store", "beam_runs",
     "beam_basins", "beam_continuation"),
    ("branch_file", "basin_file", "cluster", "beam_cluster"),
    ("sweep",),
    ("cli",),
)


def _layer(module: str) -> int:
    if module == "harvester_sweep":
        return len(LAYERS)
    name = module.split(".")[1]
    found = [i for i, layer in enumerate(LAYERS) if name in layer]
    assert found, f"{module} is in no layer of LAYERS: place it there"
    return found[0]


def test_no_module_imports_from_a_layer_above_its_own():
    for module, deps in _graph().items():
        for dep in deps:
            assert _layer(dep) <= _layer(module), f"{module} imports {dep}, a layer above it"


# Each engine and the one module outside _engine that calls it: the lane engine's period
# map, and the modal engine's (two engines, one per kind of model: docs/engine.md).
CALLERS = {"_engine": "period_map.py", "_engine.modal": "modal_map.py"}


@pytest.mark.parametrize("engine", sorted(CALLERS))
def test_each_engine_is_called_through_its_period_map_alone(engine):
    """Outside _engine, only the engine's period map calls its functions (the other
    modules read its layouts and constants)."""
    import importlib
    package = importlib.import_module(f"harvester_sweep.{engine}")
    functions = {name for name in package.__all__ if callable(getattr(package, name))
                 and name.islower()}
    alias = engine.rsplit(".", 1)[-1]
    for path in PACKAGE.glob("*.py"):
        if path.name == CALLERS[engine]:
            continue
        tree = ast.parse(path.read_text())
        used = {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)
                and isinstance(n.value, ast.Name) and n.value.id == alias}
        used |= {a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)
                 and (n.module or "").endswith(engine) for a in n.names}
        assert not used & functions, f"{path.name} calls {engine}'s {used & functions}"


def test_no_public_function_or_class_is_defined_in_two_modules():
    """A function, class or named tuple without a leading underscore is defined once in
    the package: one name, one meaning."""
    where: dict[str, list[str]] = {}
    for path in PACKAGE.rglob("*.py"):
        for node in ast.parse(path.read_text()).body:
            names = []
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                names = [node.name]
            elif isinstance(node, ast.Assign) and isinstance(node.value, ast.Call) \
                    and getattr(node.value.func, "id", "") == "namedtuple":
                names = [t.id for t in node.targets if isinstance(t, ast.Name)]
            for name in names:
                if not name.startswith("_"):
                    where.setdefault(name, []).append(_module_name(path))
    twice = {name: modules for name, modules in where.items() if len(modules) > 1}
    assert not twice, twice


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


def test_every_subpackage_is_installed():
    """pyproject.toml lists every folder of the package (the tests run from the source tree
    and would not see one left out; the notebooks and users would)."""
    import tomllib
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    folders = {_module_name(p) for p in PACKAGE.rglob("__init__.py")}
    assert folders == listed, folders ^ listed


def test_the_suites_dealing_names_its_files_once():
    """conftest.py deals the test files out by name (BEAM_FIRST, LONGEST): a file renamed
    or removed would silently fall back to the end of the run."""
    names = {}
    for node in ast.parse((ROOT / "conftest.py").read_text()).body:
        if isinstance(node, ast.Assign) and node.targets[0].id in ("BEAM_FIRST", "LONGEST"):
            names[node.targets[0].id] = ast.literal_eval(node.value)
    listed = names["BEAM_FIRST"] + names["LONGEST"]
    assert len(listed) == len(set(listed))
    for path in listed:
        assert (ROOT / path).is_file(), path
