"""The reader's layout rules: small modules, and the text-reading package below the stages."""

from __future__ import annotations

import ast
from pathlib import Path

READER = Path(__file__).resolve().parents[2] / "gauged" / "reader"
MAX_LINES = 400


def _runtime_imports(path: Path) -> set[str]:
    """Modules ``path`` imports when it runs (imports under ``if TYPE_CHECKING:`` left out)."""
    tree = ast.parse(path.read_text())
    checking = {id(n) for node in ast.walk(tree) if isinstance(node, ast.If)
                and getattr(node.test, "id", None) == "TYPE_CHECKING" for n in ast.walk(node)}
    found = set()
    for node in ast.walk(tree):
        if id(node) in checking:
            continue
        if isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return found


def test_no_reader_module_is_over_400_lines():
    sizes = {str(p.relative_to(READER)): len(p.read_text().splitlines()) for p in READER.rglob("*.py")}
    assert sizes and all(n <= MAX_LINES for n in sizes.values()), {k: v for k, v in sizes.items() if v > MAX_LINES}


def test_the_ocr_package_imports_no_stage_and_no_pipeline():
    for path in (READER / "ocr").glob("*.py"):
        wrong = {m for m in _runtime_imports(path)
                 if m.startswith(("gauged.reader.stages", "gauged.reader.pipeline", "gauged.reader.looks"))}
        assert not wrong, f"{path.name} imports {sorted(wrong)}"


def test_alarms_do_not_import_tracking():
    alarms = READER.parent / "alarms"
    for path in alarms.glob("*.py"):
        assert not {m for m in _runtime_imports(path) if m.startswith("gauged.tracking")}, path.name


def test_the_package_names_no_session_and_no_dataset_image():
    """Comments explain the wrong answer a rule prevents, not the session or the image that showed it
    (git history keeps those): no "session 22", no "held-out 000874"-style image id."""
    import re

    package = READER.parent
    pattern = re.compile(r"\bsession \d+|\b(held-out|fresh\d*|dev|synthetic|render) \d{6}\b|\(held-out \d|\b0\d{5}\.(jpg|png)",
                         re.IGNORECASE)
    allowed = {"synth/truth.py"}  # the label schema's example file name
    hits = [f"{p.relative_to(package)}:{k}" for p in package.rglob("*.py") if str(p.relative_to(package)) not in allowed
            for k, line in enumerate(p.read_text().splitlines(), start=1) if pattern.search(line)]
    assert not hits, hits
