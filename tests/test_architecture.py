"""The house's rules, checked on the source: imports follow the floors of `design.md`, no
subpackage imports another's private modules, no import cycle between subpackages, and no
function-local imports except of costly optional dependencies."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "radiometria"

# design.md, "The house, floor by floor"; floor-1 private helpers are shared by every floor.
FLOORS = {
    "constants": 1, "_checks": 1, "_types": 1, "_math": 1, "_io": 1, "_bits": 1, "_timing": 1,
    "_xla": 1,
    "_native_build": 2,  # compiles the native kernels' library: no JAX, floor-1 helpers only
    "_warmstart": 2,  # the command line's warm start: JAX, NumPy and floor-1 helpers only
    "_image_files": 2,  # image files (radiometria.camera exports them): NumPy and floor 1 only
    "radiometry": 2, "montecarlo": 2,
    "photometry": 3, "colorimetry": 3,
    "upsampling": 4, "scattering": 4, "camera": 4, "media": 4,
    "render": 5,
    "figures": 6, "cli": 6, "__main__": 6, "__init__": 6,
}  # fmt: skip
# Imports that may stay inside functions: each costs start-up time or is optional.
LAZY_OK = {"matplotlib", "trimesh", "mitsuba", "OpenEXR", "Imath", "tqdm", "scipy", "colour"}
# The command line imports each command's module when that command runs: `radiometria --help`
# starts without JAX, and the CPU device count is set before JAX is first imported.
LAZY_MODULES = {"cli.py"}


def test_every_top_level_module_has_a_floor():
    """A module missing from FLOORS would be skipped by the floor test below."""
    names = {p.stem for p in PACKAGE.glob("*.py")} | {
        p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists()
    }
    assert not names - set(FLOORS), f"add to FLOORS: {sorted(names - set(FLOORS))}"


def _modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE)
        yield path, rel.parts


def _unit(parts) -> str:
    """The floor unit a module belongs to: its subpackage, or its floor-1 module name."""
    return parts[0].removesuffix(".py")


def _resolve(parts, node: ast.ImportFrom) -> list[str] | None:
    """Absolute module path (inside radiometria) of a relative `from ... import`."""
    if node.level == 0:
        if node.module and node.module.split(".")[0] == "radiometria":
            return node.module.split(".")[1:]
        return None
    base = list(parts[:-1])
    if node.level > 1:
        base = base[: len(base) - (node.level - 1)]
    return base + (node.module.split(".") if node.module else [])


def _internal_imports():
    for path, parts in _modules():
        tree = ast.parse(path.read_text(), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                target = _resolve(parts, node)
                if target:
                    yield path, parts, target, node


def test_imports_follow_the_floors():
    wrong = []
    for path, parts, target, node in _internal_imports():
        here, there = _unit(parts), _unit(target) if target else "__init__"
        if here == there or there not in FLOORS or here not in FLOORS:
            continue
        if FLOORS[there] >= FLOORS[here] and FLOORS[here] < 6:
            wrong.append(f"{path.relative_to(PACKAGE)}:{node.lineno} imports {'.'.join(target)}")
    assert not wrong, "imports from the same or a higher floor:\n" + "\n".join(wrong)


def test_no_private_module_of_another_subpackage_is_imported():
    wrong = []
    for path, parts, target, node in _internal_imports():
        here, there = _unit(parts), _unit(target)
        if here == there or FLOORS.get(there) == 1:
            continue
        if FLOORS.get(here) == 6 and target[-1] == "_cli":
            continue  # the command line runs each subpackage's command module
        if any(p.startswith("_") for p in target[1:]):
            wrong.append(f"{path.relative_to(PACKAGE)}:{node.lineno} imports {'.'.join(target)}")
        names = [a.name for a in node.names if a.name.startswith("_")]
        if names:
            wrong.append(f"{path.relative_to(PACKAGE)}:{node.lineno} imports private {names}")
    assert not wrong, "private names imported across subpackages:\n" + "\n".join(wrong)


def test_no_import_cycle_between_modules():
    graph: dict[str, set[str]] = {}
    for _path, parts, target, _ in _internal_imports():
        src = ".".join(p.removesuffix(".py") for p in parts)
        graph.setdefault(src, set()).add(".".join(target))
    # A module imports a package: that is an edge to the package's __init__.
    nodes = set(graph) | {t for ts in graph.values() for t in ts}

    def norm(name):
        return name if name in graph or name + ".__init__" not in graph else name + ".__init__"

    edges = {n: {norm(t) for t in graph.get(n, ())} for n in nodes}
    seen, stack, cycles = {}, [], []

    def visit(n):
        seen[n] = 1
        stack.append(n)
        for m in edges.get(n, ()):
            if m.endswith("__init__") and n.startswith(m.removesuffix(".__init__")):
                continue  # a package module importing its own package's __init__ via re-export
            if seen.get(m) == 1:
                cycles.append(stack[stack.index(m) :] + [m])
            elif m not in seen:
                visit(m)
        stack.pop()
        seen[n] = 2

    for n in sorted(nodes):
        if n not in seen:
            visit(n)
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c) for c in cycles)


def test_no_function_local_imports_but_costly_ones():
    wrong = []
    for path, parts in _modules():
        if "/".join(parts) in LAZY_MODULES:
            continue
        tree = ast.parse(path.read_text(), str(path))
        for fn in ast.walk(tree):
            if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            for node in ast.walk(fn):
                if isinstance(node, ast.Import):
                    names = [a.name.split(".")[0] for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0:
                    names = [node.module.split(".")[0]]
                elif isinstance(node, ast.ImportFrom):
                    names = ["<relative>"]
                else:
                    continue
                if not set(names) <= LAZY_OK:
                    wrong.append(f"{path.relative_to(PACKAGE)}:{node.lineno} {names}")
    if wrong:
        pytest.fail("function-local imports:\n" + "\n".join(wrong))
