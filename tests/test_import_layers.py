"""The import structure docs/session.md draws, checked on the package's source (as napari's
import-linter contracts are): no import circles, no import from a lower layer into a higher one, and
nothing under ``groundstation/ui/`` or ``groundstation/export/`` that reaches the session's makers
(the pipeline, the batch path, the live runner, the loaders), directly or through other modules.

Every ``import`` counts, also one inside a function (it runs as surely, only later). ``from a import b``
points at ``a.b`` when that is a module, else at ``a``; a package's ``__init__`` is not imported
along with its submodules (as import-linter counts it).

``python tests/test_import_layers.py`` prints the circles, upward imports and forbidden paths it finds.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("groundstation", "firmware_protocol")

# Top first: a module may import its own layer and the layers below it, never one above.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("entry points", ("groundstation.cli", "groundstation.__main__", "groundstation.commands")),
    ("window", ("groundstation.ui",)),
    ("makers and exports", (
        "groundstation.export", "groundstation.session_makers.loaders", "groundstation.session_makers.factory", "groundstation.session_makers.load",
        "groundstation.session_makers.live", "groundstation.session_makers.batch", "groundstation.session_makers.estimate_run",
        "groundstation.session_makers.replay",
        "groundstation.session_makers.pipeline", "groundstation.session_makers.mavlink_front", "groundstation.session_makers.flight_log_session",
        "groundstation.logbook",
    )),
    ("playback and the product", (
        "groundstation.session.playback", "groundstation.session.product", "groundstation.session.view",
    )),
    ("the session's parts", ("groundstation.session_parts", "groundstation.autopilot", "groundstation.formats", "groundstation.sources",
                             "groundstation.recording", "groundstation.experiments", "groundstation.sim")),
    ("computation", ("groundstation.estimation", "groundstation.position", "groundstation.analysis",
                     "groundstation.datasets", "firmware_protocol")),
    ("foundations", ("groundstation",)),  # units, quaternion, errors, mounting, geodesy, readings, names, text
)
# What the window and the exports read is the product (``session.product``, ``session.view``); these
# make it, and neither may reach them, not even through another module.
MAKERS = ("groundstation.session_makers.pipeline", "groundstation.session_makers.batch", "groundstation.session_makers.estimate_run",
          "groundstation.session_makers.live", "groundstation.session_makers.factory", "groundstation.session_makers.load", "groundstation.session_makers.replay",
          "groundstation.session_makers.mavlink_front", "groundstation.session_makers.flight_log_session", "groundstation.session_makers.loaders")
READERS = ("groundstation.ui", "groundstation.export")


def modules() -> dict[str, Path]:
    out = {}
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def _type_checking(node: ast.If) -> bool:
    return isinstance(node.test, (ast.Name, ast.Attribute)) and "TYPE_CHECKING" in ast.unparse(node.test)


def imports(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """The package modules ``name`` imports (anywhere in it but under ``if TYPE_CHECKING``)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()

    def resolve(target: str) -> str | None:
        while target and target not in known:
            target = target.rpartition(".")[0]
        return target or None

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _type_checking(node):
            return
        if isinstance(node, ast.Import):
            found.update(filter(None, (resolve(alias.name) for alias in node.names)))
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, *([base] if base else [])])
            for alias in node.names:
                target = f"{base}.{alias.name}"
                found.add(target if target in known else resolve(base))
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8")))
    found.discard(None)
    found.discard(name)
    return found


def graph() -> dict[str, set[str]]:
    known = modules()
    return {name: imports(name, path, known) for name, path in known.items()}


def layer_of(module: str) -> int:
    """The index in LAYERS of the most specific prefix naming ``module``."""
    best, best_length = len(LAYERS), -1
    for index, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best_length:
                best, best_length = index, len(prefix)
    return best


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, stack, on_stack, out, counter = {}, {}, [], set(), [], [0]

    def connect(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                connect(w)
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
                out.append(sorted(component))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for v in sorted(edges):
        if v not in index:
            connect(v)
    return sorted(out)


def upward(edges: dict[str, set[str]]) -> list[tuple[str, str]]:
    return sorted((a, b) for a, targets in edges.items() for b in targets if layer_of(b) < layer_of(a))


def _within(module: str, prefixes) -> bool:
    return any(module == p or module.startswith(p + ".") for p in prefixes)


def forbidden_paths(edges: dict[str, set[str]]) -> list[list[str]]:
    """For each reader module that reaches a maker: the shortest chain of imports that does."""
    out = []
    for start in sorted(m for m in edges if _within(m, READERS)):
        previous, frontier = {start: None}, [start]
        while frontier:
            reached = next((m for m in frontier if _within(m, MAKERS)), None)
            if reached is not None:
                chain = [reached]
                while previous[chain[-1]] is not None:
                    chain.append(previous[chain[-1]])
                out.append(chain[::-1])
                break
            following = []
            for m in frontier:
                for n in sorted(edges.get(m, ())):
                    if n not in previous:
                        previous[n] = m
                        following.append(n)
            frontier = following
    return out


def test_no_import_circles():
    assert circles(graph()) == []


def test_no_import_from_a_lower_layer_into_a_higher_one():
    assert upward(graph()) == []


def test_the_window_and_the_exports_reach_no_maker_of_the_session():
    assert forbidden_paths(graph()) == []


def test_the_checker_sees_an_indirect_import_a_circle_and_an_upward_import():
    """The checks can fail: a made-up window module importing a helper that imports the pipeline."""
    edges = {"groundstation.ui.fake": {"groundstation.ui.helper"}, "groundstation.ui.helper": {"groundstation.session_makers.pipeline"},
             "groundstation.session_makers.pipeline": {"groundstation.ui.fake"}}
    assert forbidden_paths(edges) == [["groundstation.ui.fake", "groundstation.ui.helper", "groundstation.session_makers.pipeline"],
                                      ["groundstation.ui.helper", "groundstation.session_makers.pipeline"]]
    assert circles(edges) == [sorted(edges)]
    assert upward(edges) == [("groundstation.session_makers.pipeline", "groundstation.ui.fake")]


if __name__ == "__main__":
    edges = graph()
    print(f"{len(edges)} modules, {sum(map(len, edges.values()))} imports")
    found = circles(edges)
    print(f"\ncircles: {len(found)}")
    for circle in found:
        print("  " + " <-> ".join(circle))
    found = upward(edges)
    print(f"\nupward imports: {len(found)}")
    for a, b in found:
        print(f"  {a} ({LAYERS[layer_of(a)][0]}) -> {b} ({LAYERS[layer_of(b)][0]})")
    found = forbidden_paths(edges)
    print(f"\nwindow or export modules reaching a maker: {len(found)}")
    for chain in found:
        print("  " + " -> ".join(chain))
