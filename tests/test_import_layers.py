"""The import contract docs/session.md draws, declared in ``pyproject.toml`` (``[tool.importlinter]``) and
checked by import-linter, as napari checks its own: every folder and top-level module of ``groundstation/``
in one layer, importing its own layer and those below, never one above; the window and the exports reaching
no maker of the session, not even through another module; the wire protocol importing nothing of the
ground station; and no import circles, between folders or between the modules of one.

``lint-imports`` at the repository's root prints the same report.
"""

from __future__ import annotations

import copy
from pathlib import Path

import grimp
import pytest
from importlinter.adapters.user_options import TomlFileUserOptionReader
from importlinter.cli import lint_imports
from importlinter.contracts.acyclic_siblings import AcyclicSiblingsContract
from importlinter.contracts.forbidden import ForbiddenContract
from importlinter.contracts.layers import LayersContract

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = ROOT / "pyproject.toml"
OPTIONS = TomlFileUserOptionReader().read_options(str(PYPROJECT))  # as lint-imports reads them
TYPES = {kind.type_name: kind for kind in (LayersContract, ForbiddenContract, AcyclicSiblingsContract)}


def test_the_import_contracts_are_kept():
    """On failure, the captured output names each broken contract and the imports that break it."""
    assert lint_imports(config_filename=str(PYPROJECT), no_cache=True, no_logo=True) == 0


@pytest.fixture(scope="module")
def graph():
    session = OPTIONS.session_options  # its booleans as text, as the reader hands them to the contracts
    return grimp.build_graph(*session["root_packages"], cache_dir=None,
                             exclude_type_checking_imports=str(session["exclude_type_checking_imports"]).lower() == "true")


def broken(graph, *imports: tuple[str, str]) -> set[str]:
    """The ids of the declared contracts that the package breaks with ``imports`` (importer, imported) added."""
    graph = copy.deepcopy(graph)
    for importer, imported in imports:
        graph.add_import(importer=importer, imported=imported)
    out = set()
    for declared in OPTIONS.contracts_options:
        contract = TYPES[declared["type"]](name=declared["name"], session_options=OPTIONS.session_options, contract_options=declared)
        if not contract.check(graph, verbose=False).kept:
            out.add(declared["id"])
    return out


@pytest.mark.parametrize(("imports", "contracts"), [
    pytest.param([("groundstation.ui.fake", "groundstation.ui.helper"), ("groundstation.ui.helper", "groundstation.session_makers.pipeline")],
                 {"readers"}, id="the window reaching the pipeline through a helper"),
    pytest.param([("groundstation.session_parts.table", "groundstation.session.view")], {"layers", "acyclic"},
                 id="a part importing the product above it (which imports the parts: a circle of folders)"),
    pytest.param([("groundstation.autopilot.records", "groundstation.autopilot.vehicle")], {"acyclic"},
                 id="two modules of one folder importing each other"),
    pytest.param([("groundstation.sensors", "groundstation.units")], {"layers"}, id="a new top-level module in no layer"),
    pytest.param([("firmware_protocol.decoder", "groundstation.units")], {"protocol"}, id="the wire protocol importing the ground station"),
])
def test_each_contract_breaks_on_what_it_forbids(graph, imports, contracts):
    assert broken(graph) == set()
    assert broken(graph, *imports) == contracts
