"""The Python package's import graph (grimp; function-local and ``TYPE_CHECKING`` imports count):
no import circles, and dependencies point one way, from the papers down to the extension module,
as the rooms of the core do (``crates/rfcore/tests/architecture.rs``)::

    papers  ->  studies  ->  control  ->  flight, allocation  ->  analysis  ->  _typing, _util, _rfcore

plus the command line on top (it only calls the public API), the package's facade and the
deprecated module names above everything, and ``plotting`` beside the rooms: any room may draw
through it, and it only reads results. No paper imports another paper. ``docs/architecture.md``
draws the picture.
"""

from __future__ import annotations

import grimp
import pytest

PACKAGE = "rotorfault"

#: Modules at the top of the package that keep an old import path working for one release.
DEPRECATED_SHIMS = ["airframe", "campaign", "certify", "controllability", "design", "scan", "scenario", "simulation"]

#: Layers, highest first, by the first name under ``rotorfault``: a module may import from its own
#: room (no circles) and from lower layers. Rooms in one layer do not import each other.
LAYERS = [
    ["", "__main__", "vpp", *DEPRECATED_SHIMS],
    ["cli"],
    ["papers"],
    ["studies"],
    ["control"],
    ["flight", "allocation"],
    ["analysis"],
    ["_typing", "_util"],
]
#: Beside the layers: any room may import it; it imports only these (it reads results, and the
#: words of a verdict).
PLOTTING = "plotting"
PLOTTING_MAY_IMPORT = ("rotorfault._util", "rotorfault._typing", "rotorfault.flight.outcomes")
#: The papers' shared machinery (the report writer, the printed-number rows, the decisions table,
#: the reproduce-all report); every other module of ``papers`` belongs to the paper its name starts with.
PAPERS_SHARED = {"rotorfault.papers._report", "rotorfault.papers._numbers", "rotorfault.papers.decisions",
                 "rotorfault.papers.reproduce"}


@pytest.fixture(scope="module")
def graph() -> grimp.ImportGraph:
    graph = grimp.build_graph(PACKAGE, cache_dir=None)
    # grimp does not see the compiled extension: ``from .. import _rfcore`` reads as an import of
    # the package itself (the public facade, which imports everything). Drop exactly those edges;
    # any other import of the facade from inside the package stays and shows up as a circle.
    for module in graph.find_modules_that_directly_import(PACKAGE):
        details = graph.get_import_details(importer=module, imported=PACKAGE)
        if details and all("_rfcore" in d["line_contents"] for d in details):
            graph.remove_import(importer=module, imported=PACKAGE)
    return graph


def _top(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _layer(module: str) -> int | None:
    top = _top(module)
    for k, names in enumerate(LAYERS):
        if top in names:
            return k
    return None


def _imports(graph: grimp.ImportGraph, prefix: str) -> list[tuple[str, str]]:
    """Every direct import from a module of ``prefix`` (the module or below it)."""
    return sorted(
        (m, imported)
        for m in graph.modules
        if m == prefix or m.startswith(prefix + ".")
        for imported in graph.find_modules_directly_imported_by(m)
    )


def test_no_import_circles(graph: grimp.ImportGraph) -> None:
    cycles = []
    for module in sorted(graph.modules):
        for imported in graph.find_modules_directly_imported_by(module):
            if imported != module and graph.chain_exists(imported, module):
                cycles.append(graph.find_shortest_chain(imported, module) or (imported, module))
                cycles[-1] = (module, *cycles[-1])
    assert not cycles, "import circles:\n" + "\n".join(" -> ".join(c) for c in cycles)


def test_every_module_has_a_room(graph: grimp.ImportGraph) -> None:
    unplaced = sorted(m for m in graph.modules if _layer(m) is None and _top(m) != PLOTTING)
    assert not unplaced, f"modules missing from LAYERS: {unplaced}"


def test_imports_point_down_the_layers(graph: grimp.ImportGraph) -> None:
    """No direct import (module level, inside a function or for type checking) goes to a higher
    layer or across to another room of the same layer (flight and allocation are independent)."""
    wrong = []
    for module in sorted(graph.modules):
        source = _layer(module)
        if source is None:
            continue
        for imported in graph.find_modules_directly_imported_by(module):
            target = _layer(imported)
            if target is None or _top(imported) == _top(module):
                continue
            if target < source or (target == source and source != 0):
                wrong.append(f"{module} -> {imported}")
    assert not wrong, "imports against the layering:\n" + "\n".join(wrong)


@pytest.mark.parametrize(
    ("importer", "imported"),
    [
        ("rotorfault.flight", "rotorfault.control"),
        ("rotorfault.flight", "rotorfault.allocation"),
        ("rotorfault.allocation", "rotorfault.flight"),
        ("rotorfault.allocation", "rotorfault.control"),
        ("rotorfault.analysis", "rotorfault.flight"),
        ("rotorfault.control", "rotorfault.studies"),
        ("rotorfault.control", "rotorfault.papers"),
        ("rotorfault.control", "rotorfault.cli"),
        ("rotorfault.studies", "rotorfault.papers"),
        ("rotorfault.papers", "rotorfault.cli"),
        ("rotorfault.plotting", "rotorfault.control"),
        ("rotorfault.plotting", "rotorfault.studies"),
        ("rotorfault.plotting", "rotorfault.papers"),
    ],
)
def test_forbidden_dependencies(graph: grimp.ImportGraph, importer: str, imported: str) -> None:
    """The named rules of the layering, also indirectly (any chain of imports)."""
    chain = graph.find_shortest_chain(importer=importer, imported=imported, as_packages=True)
    assert chain is None, " -> ".join(chain or ())


def test_plotting_only_reads_results(graph: grimp.ImportGraph) -> None:
    """Plotting imports nothing of the rooms but the words of a verdict: it draws what a
    computation returned, it computes nothing a room owns."""
    wrong = [
        f"{m} -> {imported}"
        for m, imported in _imports(graph, f"{PACKAGE}.{PLOTTING}")
        if _top(imported) != PLOTTING and not any(imported == p or imported.startswith(p + ".") for p in PLOTTING_MAY_IMPORT)
    ]
    assert not wrong, "plotting imports beyond results:\n" + "\n".join(wrong)


def _paper(module: str) -> str | None:
    """The paper a module of ``papers`` belongs to (``lanzon_checks`` is Lanzon's), None if shared
    (or the room's index, ``rotorfault.papers`` itself, which lists the papers)."""
    if module in PAPERS_SHARED or module == f"{PACKAGE}.papers":
        return None
    return module.split(".")[2].split("_")[0]


def test_no_paper_imports_another_paper(graph: grimp.ImportGraph) -> None:
    wrong = []
    for m, imported in _imports(graph, f"{PACKAGE}.papers"):
        if _top(imported) != "papers":
            continue
        mine, theirs = _paper(m), _paper(imported)
        if m != f"{PACKAGE}.papers" and theirs is not None and theirs != mine:
            wrong.append(f"{m} -> {imported}")
    assert not wrong, "papers importing other papers:\n" + "\n".join(wrong)


def test_the_papers_shared_machinery_imports_no_paper(graph: grimp.ImportGraph) -> None:
    """The report writer and the printed-number rows serve every paper and know none (the
    reproduce-all report finds the papers by name, on use)."""
    wrong = [f"{m} -> {i}" for m, i in _imports(graph, f"{PACKAGE}.papers") if m in PAPERS_SHARED and _top(i) == "papers" and _paper(i) is not None]
    assert not wrong, "\n".join(wrong)


def test_the_cli_only_calls_the_public_api(graph: grimp.ImportGraph) -> None:
    """Outside itself the CLI imports the facade, the rooms' public modules and names, the option
    types (``_typing``) and the shared output helpers (``_util``): never the extension module, a
    room's private module (``_report``, ``_formats``, ...) or a private name."""
    wrong = []
    for m, imported in _imports(graph, f"{PACKAGE}.cli"):
        if _top(imported) == "cli":
            continue
        parts = imported.split(".")[1:]
        if parts and parts[0] in ("_typing", "_util"):
            continue
        private_module = any(p.startswith("_") for p in parts)
        lines = [d["line_contents"] for d in graph.get_import_details(importer=m, imported=imported)]
        private_name = any(
            name.strip().startswith("_")
            for line in lines
            if " import " in line
            for name in line.split(" import ", 1)[1].replace("(", "").replace(")", "").split(",")
        )
        if private_module or private_name or imported == PACKAGE and any("_rfcore" in line for line in lines):
            wrong.append(f"{m} -> {imported}: {'; '.join(lines)}")
    assert not wrong, "the CLI reaches past the public API:\n" + "\n".join(wrong)


def test_only_the_entry_points_import_cli(graph: grimp.ImportGraph) -> None:
    importers = {m for m in graph.find_modules_that_directly_import("rotorfault.cli") if _top(m) != "cli"}
    assert importers <= {"rotorfault.__main__"}, importers


def test_nothing_inside_imports_a_deprecated_name(graph: grimp.ImportGraph) -> None:
    """The old module names are for users, for one release: the package itself uses the rooms."""
    shims = {f"{PACKAGE}.{name}" for name in DEPRECATED_SHIMS}
    wrong = sorted(f"{m} -> {i}" for m in graph.modules for i in graph.find_modules_directly_imported_by(m) if i in shims)
    assert not wrong, "\n".join(wrong)


def test_every_room_says_what_lives_there_and_what_it_may_import() -> None:
    """Each room's ``__init__`` docstring is one paragraph on what lives there and one on what it
    may import (the rules this file enforces)."""
    import importlib

    for room in ("analysis", "flight", "allocation", "control", "studies", "plotting", "papers", "cli", "_util"):
        doc = importlib.import_module(f"{PACKAGE}.{room}").__doc__ or ""
        assert len(doc.split()) > 40 and "import" in doc, f"rotorfault.{room}: its docstring must say what lives there and what it may import"


def test_import_stays_light() -> None:
    """``import rotorfault`` (and the CLI module) loads neither scipy, python-control nor
    matplotlib: those cost about two seconds and only some calls need them (issue 15; the
    timing itself is measured by benches/startup.py, not here)."""
    import subprocess
    import sys

    code = (
        "import sys, rotorfault, rotorfault.cli; "
        "print(sorted(m for m in ('scipy', 'control', 'matplotlib') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]", done.stdout
