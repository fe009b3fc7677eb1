"""The notebooks in ``examples/`` (issue 31): each runs top to bottom in a fresh kernel, its own
checks (the last cells assert the key numbers) pass, and nothing lands on its standard error; the
repository holds them without outputs or execution counts.

They run with nbclient in a temporary copy of ``examples/`` beside a link to ``tests/data`` (the
PX4 parameter file the certify notebook reads), so the figures they save do not touch the clone.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
NOTEBOOKS = sorted(EXAMPLES.glob("*.ipynb"))
#: What the issue asks a notebook to cover, by file: each must exist.
EXPECTED = {"du-analysis", "ke-flight", "lanzon-design", "wang-vpp", "certify-px4", "campaign"}
#: A cell that takes longer than this is a notebook too big for CI (they take seconds).
CELL_TIMEOUT_S = 120


def test_the_notebooks_the_issue_names_exist() -> None:
    assert {path.stem for path in NOTEBOOKS} == EXPECTED


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_is_stored_without_outputs(path: Path) -> None:
    notebook = json.loads(path.read_text(encoding="utf-8"))
    for index, cell in enumerate(notebook["cells"]):
        if cell["cell_type"] == "code":
            assert cell.get("outputs") == [], f"{path.name}: cell {index} holds outputs (strip them)"
            assert cell.get("execution_count") is None, f"{path.name}: cell {index} has an execution count"
    sources = "".join("".join(c["source"]) for c in notebook["cells"] if c["cell_type"] == "code")
    assert "assert " in sources, f"{path.name} checks none of its numbers"
    assert ".to_pandas()" in sources, f"{path.name} shows no DataFrame"


def execute(notebook: Any, work: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Runs ``notebook`` in a fresh kernel in ``work``; a cell that raises raises here."""
    # jupyter_client warns about its old path layout unless told to use the platform's directories.
    monkeypatch.setenv("JUPYTER_PLATFORM_DIRS", "1")
    nbclient = pytest.importorskip("nbclient")
    client = nbclient.NotebookClient(notebook, timeout=CELL_TIMEOUT_S, kernel_name="python3",
                                     resources={"metadata": {"path": str(work)}})
    client.execute()


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    nbformat = pytest.importorskip("nbformat")
    work = tmp_path / "examples"
    shutil.copytree(EXAMPLES, work)
    (tmp_path / "tests").mkdir()
    os.symlink(ROOT / "tests" / "data", tmp_path / "tests" / "data")
    notebook = nbformat.read(path, as_version=4)
    execute(notebook, work, monkeypatch)
    for index, cell in enumerate(notebook.cells):
        for output in cell.get("outputs", []):
            assert not (output["output_type"] == "stream" and output["name"] == "stderr"), (
                f"{path.name}: cell {index} wrote to stderr: {output['text'][:500]}")
    shown = [o for cell in notebook.cells for o in cell.get("outputs", [])]
    assert any("text/html" in o.get("data", {}) for o in shown), f"{path.name} shows no table"


def test_a_wrong_number_fails_the_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A notebook whose check fails fails its test: the checking cell's AssertionError reaches
    the runner (Du's Table II ACAI, 1.4861, checked as 1.4862)."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    notebook = nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_code_cell("import rotorfault as rf\nhexa = rf.Airframe.preset('hexa-pnpnpn')"),
        nbformat.v4.new_code_cell("assert round(rf.acai(hexa), 4) == 1.4862"),
    ])
    with pytest.raises(nbclient.exceptions.CellExecutionError, match="AssertionError"):
        execute(notebook, tmp_path, monkeypatch)
