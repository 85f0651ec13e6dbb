"""The package's layers import only down the pipeline (read from the source with ast, nothing is imported).

Order, bottom to top: ``geometry``, ``utils`` and ``errors`` (the foundation; they import no stage), then
``assets`` -> ``grasps`` -> ``sdf`` -> ``models`` -> ``scenes`` -> ``training`` -> ``inference`` ->
``evaluation``. ``viz`` (pictures) and ``cli``, ``commands``, ``demo``, ``predict``, ``recipe`` sit on top and may
import anything.
Every import counts, including the ones inside functions (they are what keeps the CLI cheap to start, not a
way around the order).
"""

from __future__ import annotations

import ast
from pathlib import Path

import centerart

PACKAGE = Path(centerart.__file__).parent
FOUNDATION = ("geometry", "utils", "errors")
PIPELINE = ("assets", "grasps", "sdf", "models", "scenes", "training", "inference", "evaluation")
TOP = ("viz", "cli", "commands", "demo", "predict", "recipe")
RANK = {**dict.fromkeys(FOUNDATION, 0), **{name: i + 1 for i, name in enumerate(PIPELINE)}}


def _layer(path: Path) -> str:
    rel = path.relative_to(PACKAGE)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def import_edges() -> list[tuple[str, str, str]]:
    """(importing layer, imported layer, 'file:line') for every import of another centerart layer."""
    edges = []
    for path in sorted(PACKAGE.rglob("*.py")):
        src = _layer(path)
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module] + [f"{node.module}.{a.name}" for a in node.names if node.module == "centerart"]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            for name in names:
                parts = name.split(".")
                if parts[0] == "centerart" and len(parts) > 1 and parts[1] != src:
                    edges.append((src, parts[1], f"{path.relative_to(PACKAGE)}:{node.lineno}"))
    return edges


def test_every_module_has_a_layer():
    layers = {_layer(p) for p in PACKAGE.rglob("*.py")} - {"__init__"}
    assert layers <= set(RANK) | set(TOP), layers - set(RANK) - set(TOP)


def test_imports_point_down_the_pipeline():
    upward = [
        f"{where}: {src} imports {dst}"
        for src, dst, where in import_edges()
        if src not in TOP and (dst in TOP or RANK[dst] > RANK[src])
    ]
    assert not upward, "\n".join(upward)


def test_no_two_layers_import_each_other():
    pairs = {(src, dst) for src, dst, _ in import_edges()}
    mutual = sorted({tuple(sorted(p)) for p in pairs if p[::-1] in pairs})
    assert not mutual, mutual


def test_the_check_sees_upward_imports(tmp_path, monkeypatch):
    # The checker itself: an upward import written into a copy of a bottom module must be reported.
    fake = tmp_path / "centerart"
    (fake / "geometry").mkdir(parents=True)
    (fake / "geometry" / "bad.py").write_text("def f():\n    from centerart.models import decoder\n")
    monkeypatch.setitem(globals(), "PACKAGE", fake)
    assert import_edges() == [("geometry", "models", "geometry/bad.py:2")]
