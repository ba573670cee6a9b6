"""The README's plan is on its first screen, and its tables of export formats and source forms are the
registries' (``export.request.FORMATS``, ``sources.spec.SCHEMES``): a format or a scheme added to its
registry and not to the README fails here, and so does a row the registry does not have. Every screenshot it
shows is one the screenshot driver writes (four were taken by hand once and never again)."""

import re
from pathlib import Path

from groundstation.export.request import FORMATS
from groundstation.sources.spec import SCHEMES

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
SCREENSHOT_DRIVER = ROOT / "docs" / "screenshots" / "take.py"
FIRST_SCREEN_LINES = 25  # what a terminal or a repository page shows before one scrolls


def table_after(header: str) -> list[list[str]]:
    """The cells of the rows of the README's table whose header row is ``header``."""
    start = README.index(header) + 2  # the header, then |---|
    rows = []
    for line in README[start:]:
        if not line.startswith("|"):
            break
        rows.append([cell.strip() for cell in line.strip("|").split(" | ")])
    return rows


def ticked(cell: str) -> list[str]:
    return re.findall(r"`([^`]+)`", cell)


def test_the_two_commands_come_first_and_the_plan_is_on_the_first_screen():
    fence = [i for i, line in enumerate(README) if line.startswith("```")]
    commands = README[fence[0] + 1:fence[1]]
    assert len(commands) == 2 and "groundstation app --demo" in commands[0] and commands[1].endswith("pytest")
    plan = README.index("## How it is built")
    assert plan < FIRST_SCREEN_LINES
    assert any(line.startswith("![") for line in README[fence[1]:plan])  # the screenshot before it
    length = next(i for i, line in enumerate(README) if i > plan and line.startswith("#")) - plan
    assert length <= 30, f"the architecture section is {length} lines"


def test_the_export_formats_table_is_the_registrys():
    rows = table_after("| format | name ends in | what it holds |")
    assert [(row[0], ticked(row[1])) for row in rows] == [(f.name, [f.suffix]) for f in FORMATS.values()]


def test_the_sources_table_is_the_registrys():
    rows = table_after("| source string | what |")
    assert [ticked(row[0]) for row in rows] == [list(scheme.forms) for scheme in SCHEMES.values()]


def test_every_screenshot_of_the_readme_is_retaken_by_the_driver():
    shown = set(re.findall(r"\(docs/screenshots/([^)]+\.png)\)", "\n".join(README)))
    written = set(re.findall(r'"([\w-]+\.png)"', SCREENSHOT_DRIVER.read_text(encoding="utf-8")))
    assert len(shown) >= 12 and shown <= written, f"taken by no script: {sorted(shown - written)}"
