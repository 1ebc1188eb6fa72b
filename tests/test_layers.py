"""pydiag's architecture, read from the code: stages import only their own or lower
stages, and no module imports itself back through a circle.

Every ``import`` and ``from ... import`` of every module counts, at any depth (a
function-level import is still a dependency).
"""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "pydiag"
#: The stages, lowest first (the order of pydiag/__init__.py's table).
STAGES = ("core", "signal", "io", "fmu", "gear", "model", "fit", "loop", "diagnose", "app")
MAX_CLI_LINES = 400


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path) -> set[str]:
    """The pydiag modules a file imports (``from pydiag.x import y`` may name module y)."""
    tree = ast.parse(path.read_text(), str(path))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.split(".")[0] == "pydiag"}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] == "pydiag":
                found.add(node.module)
                found |= {f"{node.module}.{a.name}" for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level:
            raise AssertionError(f"{path}: relative import; use absolute pydiag.* imports")
    return found


def graph() -> dict[str, set[str]]:
    files = {module_name(p): p for p in PACKAGE.rglob("*.py") if "native" not in p.parts}
    return {name: {m for m in imports_of(path) if m in files and m != name}
            for name, path in files.items()}


def stage_of(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in STAGES else None


def test_every_module_belongs_to_a_stage():
    loose = [m for m in graph() if m not in ("pydiag", "pydiag.__main__") and stage_of(m) is None]
    assert loose == [], f"modules outside the stage folders: {loose}"


def test_no_upward_import():
    rank = {s: i for i, s in enumerate(STAGES)}
    upward = [(m, d) for m, deps in graph().items() for d in deps
              if stage_of(m) and stage_of(d) and rank[stage_of(d)] > rank[stage_of(m)]]
    assert upward == [], "a stage imports a higher one:\n" + "\n".join(f"{m} -> {d}" for m, d in upward)


def test_package_init_imports_no_stage():
    # importing any pydiag module runs pydiag/__init__.py first: it must not pull stages in
    assert graph()["pydiag"] == set()


def find_cycle(edges: dict[str, set[str]]) -> list[str] | None:
    colour: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        colour[node] = 1
        stack.append(node)
        for nxt in sorted(edges.get(node, ())):
            if colour.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if colour.get(nxt) is None and (cycle := visit(nxt)):
                return cycle
        stack.pop()
        colour[node] = 2
        return None

    for node in sorted(edges):
        if colour.get(node) is None and (cycle := visit(node)):
            return cycle
    return None


def test_no_import_circle():
    cycle = find_cycle(graph())
    assert cycle is None, "import circle: " + " -> ".join(cycle)


def test_the_checks_can_fail():
    """The cycle finder and the stage ranking catch what they are for."""
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None
    assert stage_of("pydiag.fit.problem") == "fit" and stage_of("pydiag.other") is None


@pytest.mark.parametrize("path", sorted((PACKAGE / "app").glob("*.py")), ids=lambda p: p.name)
def test_cli_modules_stay_small(path):
    assert len(path.read_text().splitlines()) <= MAX_CLI_LINES


#: A module longer than this says in its docstring why it is one concern ("One concern: ...").
MAX_MODULE_LINES = 400


@pytest.mark.parametrize("path", sorted(p for p in PACKAGE.rglob("*.py") if "native" not in p.parts),
                         ids=lambda p: str(p.relative_to(PACKAGE)))
def test_a_long_module_is_one_concern_and_says_so(path):
    text = path.read_text()
    if len(text.splitlines()) > MAX_MODULE_LINES:
        doc = ast.get_docstring(ast.parse(text)) or ""
        assert "One concern:" in doc, f"{path.name}: {len(text.splitlines())} lines"


def test_at_most_two_modules_are_long():
    """A long module is the exception (issue 58: at most two over the bound)."""
    long = sorted(str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py")
                  if "native" not in p.parts and len(p.read_text().splitlines()) > MAX_MODULE_LINES)
    assert len(long) <= 2, long


def test_effect_hints_take_the_gear_stages_peak_type():
    """The catalogue's hints read residual peaks: typed against the gear stage's Peak, not a
    type of the loop above it."""
    import inspect
    import typing

    from pydiag.gear.effects import EFFECTS
    from pydiag.gear.peaks import Peak
    hinted = [e for e in EFFECTS.values() if e.hint is not None]
    assert hinted
    for effect in hinted:
        hints = typing.get_type_hints(effect.hint)
        first = next(iter(inspect.signature(effect.hint).parameters))
        assert hints[first] == list[Peak], (effect.key, hints)


def test_the_command_line_starts_without_the_heavy_libraries():
    """Every command's start imports the CLI; scipy.signal, scipy.stats, scipy.optimize,
    scipy.interpolate and pandas took 0.8 of its 1.1 s, for commands (inspect, history,
    simulate, a usage error) most of which never use them: they are imported where used."""
    import subprocess
    import sys
    heavy = ["scipy.signal", "scipy.stats", "scipy.optimize", "scipy.interpolate", "pandas"]
    code = ("import sys, pydiag.app.cli; print(' '.join(m for m in %r if m in sys.modules))"
            % heavy)
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=PACKAGE.parent)
    assert res.returncode == 0, res.stderr
    assert res.stdout.split() == [], res.stdout


@pytest.mark.parametrize("name, most", [("README.md", 200), ("bench/RESULTS.md", 600)])
def test_the_front_door_and_the_results_stay_short(name, most):
    """The README is a front door and RESULTS the current tables (history goes to
    bench/CHANGELOG.md): issue 58's bounds."""
    assert len((PACKAGE.parent / name).read_text().splitlines()) <= most
