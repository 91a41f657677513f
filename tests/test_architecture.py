"""The package's architecture holds: the layers of docs/architecture.md, and no import cycle between modules.

Both count every import statement, those inside functions and under ``if TYPE_CHECKING:`` included (grimp reads
them all): a type named across two modules ties them as much as a call does.
"""

from __future__ import annotations

from pathlib import Path

import pytest

grimp = pytest.importorskip("grimp")
pytest.importorskip("importlinter")

ROOT = Path(__file__).resolve().parents[1]


def test_the_import_contracts_of_pyproject_are_kept(capsys):
    from importlinter.cli import EXIT_STATUS_SUCCESS, lint_imports

    status = lint_imports(config_filename=str(ROOT / "pyproject.toml"), no_cache=True)
    report = capsys.readouterr().out
    assert "Layers, top to bottom KEPT" in report
    assert status == EXIT_STATUS_SUCCESS, report


def test_no_module_imports_itself_through_others():
    graph = grimp.build_graph("rtgait", exclude_type_checking_imports=False)
    cycles = []
    for module in sorted(graph.modules):
        for imported in graph.find_modules_directly_imported_by(module):
            # A package importing its own submodule and back is the usual re-export, not a cycle of concepts.
            if imported.startswith(module + "."):
                continue
            chain = graph.find_shortest_chain(importer=imported, imported=module)
            if chain is not None:
                cycles.append(" -> ".join((module, *chain)))
    assert cycles == []
