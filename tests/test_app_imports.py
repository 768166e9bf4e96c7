"""The app's import structure: the window is wiring, so its parts (scene files, runs, drawing,
exports, modes, ...) never import it, and the app's modules import each other without a cycle."""

import ast
from pathlib import Path

APP = Path(__file__).resolve().parents[1] / "app"


def imports() -> dict[str, set[str]]:
    """Each app module's imports of other app modules (``from .x import``, ``from . import x``),
    also those made inside functions."""
    graph = {}
    for path in APP.glob("*.py"):
        found = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                if node.module:
                    found.add(node.module.split(".")[0])
                else:
                    found.update(alias.name for alias in node.names)
        graph[path.stem] = found
    return graph


def test_only_the_entry_points_import_the_window():
    graph = imports()
    assert {name for name, found in graph.items() if "window" in found} == {"main", "responsiveness"}
    assert {"runs", "drawing", "scene_files", "exports", "modes", "compare_mode"} <= graph["window"]


def test_the_app_modules_import_each_other_without_a_cycle():
    graph = imports()
    done, path = set(), []

    def visit(name):
        if name in path:
            raise AssertionError("import cycle: " + " -> ".join(path[path.index(name):] + [name]))
        if name in done or name not in graph:
            return
        path.append(name)
        for other in sorted(graph[name]):
            visit(other)
        path.pop()
        done.add(name)

    for name in sorted(graph):
        visit(name)
