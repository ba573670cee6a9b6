"""Only groundstation/ui imports Qt: the core stays importable and testable without a display."""

import ast
from pathlib import Path

import groundstation

QT_MODULES = ("PySide6", "pyqtgraph", "shiboken6", "PyQt5", "PyQt6")


def imported_modules(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.module


def test_only_the_ui_package_imports_qt():
    package = Path(groundstation.__file__).parent
    offenders = []
    for path in sorted(package.rglob("*.py")):
        if path.relative_to(package).parts[0] == "ui":
            continue
        for module in imported_modules(ast.parse(path.read_text(encoding="utf-8"))):
            if module.split(".")[0] in QT_MODULES:
                offenders.append(f"{path.relative_to(package.parent)} imports {module}")
    assert not offenders, offenders
    assert any(True for _ in (package / "ui").glob("*.py"))  # the walk really saw the package
