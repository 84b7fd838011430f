"""The package layering holds and nothing imports in a circle.

Layers, lowest first (a package may import only packages of lower layers, its own modules, and
the leaf utilities)::

    registry, task_index, errors, validate,          leaf utilities (task_index: the task ids,
    contacts, rendering, known_warnings, jsonable,    horizon and Default, shared by every layer;
    html_kit, atomic                                  html_kit: the reports' page, tables, figures;
                                                      atomic: the one atomic file write;
                                                      errors, the user-error root, is below the rest)
    agents, assets, asset_pipeline                    the robot; objects and their pipeline
    tasks, sysid                                      envs (on agents + assets); sysid (on agents)
    perturbations                                     reconfiguration hooks on tasks
    expert                                            scripted policy on tasks
    eval                                              policies, runner, metrics, report
    lerobot, lerobot_env_realm                        LeRobot export and env plugin
    cli, demo, render_cli, realm_ms/__init__,         entry points (may import anything; registration
    registration                                      loads the task pack on an env's first make)

Imports inside functions and under ``if TYPE_CHECKING:`` count too: a lazy import still ties the
two modules together, and an annotation-only one still says each needs the other to be read.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("realm_ms", "asset_pipeline", "lerobot_env_realm")
LEAVES = {"realm_ms.registry", "realm_ms.task_index", "realm_ms.known_warnings", "realm_ms.errors", "realm_ms.validate", "realm_ms.contacts", "realm_ms.rendering",
          "realm_ms.jsonable", "realm_ms.html_kit", "realm_ms.atomic"}
LAYERS = [
    {"realm_ms.agents", "realm_ms.assets", "asset_pipeline"},
    {"realm_ms.tasks", "realm_ms.sysid"},
    {"realm_ms.perturbations"},
    {"realm_ms.expert"},
    {"realm_ms.eval"},
    {"realm_ms.lerobot", "lerobot_env_realm"},
]
ENTRY_POINTS = {"realm_ms", "realm_ms.registration", "realm_ms.cli", "realm_ms.demo", "realm_ms.render_cli", "realm_ms.__main__"}
# same-layer edges that are NOT allowed (sysid replays the benchmark's own robot, never its tasks)
FORBIDDEN_SAME_LAYER = {("realm_ms.sysid", "realm_ms.tasks"), ("realm_ms.tasks", "realm_ms.sysid"),
                        ("realm_ms.agents", "realm_ms.assets"), ("realm_ms.assets", "realm_ms.agents")}


def module_name(path: Path) -> str:
    mod = ".".join(path.relative_to(ROOT).with_suffix("").parts)
    return mod.removesuffix(".__init__")


def package_of(mod: str) -> str:
    parts = mod.split(".")
    return ".".join(parts[:2]) if parts[0] == "realm_ms" and len(parts) > 1 else parts[0]


def imports(path: Path) -> set[str]:
    """Every project module ``path`` imports: at module level, inside functions, under ``TYPE_CHECKING``."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.add(node.module)
            out |= {f"{node.module}.{a.name}" for a in node.names}
    return {m for m in out if m.split(".")[0] in PACKAGES}


def project_modules() -> dict[str, Path]:
    return {module_name(p): p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py") if (ROOT / pkg).exists()}


def graph() -> dict[str, set[str]]:
    mods = project_modules()
    g = defaultdict(set)
    for mod, path in mods.items():
        for m in imports(path):
            while m not in mods and "." in m:  # `from pkg.mod import name` -> pkg.mod
                m = m.rsplit(".", 1)[0]
            if m in mods and m != mod:
                g[mod].add(m)
    return g


def layer(pkg: str) -> int:
    if pkg in LEAVES:
        return -1
    for i, members in enumerate(LAYERS):
        if pkg in members:
            return i
    raise AssertionError(f"package {pkg} is not placed in a layer: add it to tests/test_layering.py and docs/architecture.md")


def test_every_import_goes_down_the_layers():
    bad = []
    for mod, deps in graph().items():
        src = package_of(mod)
        if src in ENTRY_POINTS:
            continue
        for dep in deps:
            dst = package_of(dep)
            if dst == src or dst in LEAVES or dep == "realm_ms":  # the root: register_envs, __version__
                continue
            if dst in ENTRY_POINTS or layer(dst) > layer(src) or (src, dst) in FORBIDDEN_SAME_LAYER or (
                layer(src) == -1 and dst not in LEAVES
            ):
                bad.append(f"{mod} -> {dep}")
    assert not bad, "imports against the layering:\n" + "\n".join(sorted(bad))


def test_leaf_utilities_import_no_other_project_module():
    # except the user-error root, which sits below the other leaves (they raise its kinds)
    g = graph()
    bad = [f"{m} -> {d}" for m in g if m in LEAVES for d in g[m] if d != "realm_ms.errors"]
    assert not bad, bad


def test_no_import_cycles():
    g = graph()
    g = {m: {d for d in ds if d not in ENTRY_POINTS} for m, ds in g.items() if m not in ENTRY_POINTS}
    # a submodule importing its own package's __init__ (which imports its submodules) is not a cycle
    def edges(m):
        return {d for d in g.get(m, ()) if not m.startswith(d + ".")}

    index, low, stack, on, cycles, counter = {}, {}, [], set(), [], [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges(v):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in list(g):
        if v not in index:
            strong(v)
    assert not cycles, "modules that import each other (directly or around a loop):\n" + "\n".join(map(str, cycles))


@pytest.mark.parametrize("pkg", ["realm_ms.registry", "realm_ms.agents", "realm_ms.assets", "realm_ms.tasks",
                                 "realm_ms.sysid", "realm_ms.perturbations", "realm_ms.expert", "realm_ms.eval"])
def test_package_imports_in_isolation(pkg):
    r = subprocess.run([sys.executable, "-c", f"import {pkg}"], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
