"""The Python package's import graph (grimp; function-local imports count): no import circles,
and dependencies point one way, from the base to the command line::

    _convert, _typing  <-  _progress  <-  _stream  <-  airframe  <-  controllability, scan,
        allocation, simulation  <-  design  <-  control  <-  papers  <-  cli

(``scenario``, the ``rotorfault simulate`` file, may use ``control``; the package's
``__init__``, the public facade, sits on top.)
"""

from __future__ import annotations

import grimp
import pytest

PACKAGE = "rotorfault"

#: Layers, highest first: a module may import from its own layer (no circles) and lower ones.
LAYERS = [
    ["", "cli", "__main__"],
    ["papers", "scenario", "campaign", "vpp", "certify"],
    ["control"],
    ["design"],
    ["controllability", "scan", "allocation", "simulation", "relaxed_hover"],
    ["airframe"],
    ["_stream"],
    ["_progress", "_formats"],
    ["_convert", "_typing", "_output"],
]


@pytest.fixture(scope="module")
def graph() -> grimp.ImportGraph:
    graph = grimp.build_graph(PACKAGE, cache_dir=None)
    # grimp does not see the compiled extension: ``from . import _rfcore`` reads as an import of
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


def test_no_import_circles(graph: grimp.ImportGraph) -> None:
    cycles = []
    for module in sorted(graph.modules):
        for imported in graph.find_modules_directly_imported_by(module):
            if imported != module and graph.chain_exists(imported, module):
                cycles.append(graph.find_shortest_chain(imported, module) or (imported, module))
                cycles[-1] = (module, *cycles[-1])
    assert not cycles, "import circles:\n" + "\n".join(" -> ".join(c) for c in cycles)


def test_every_module_has_a_layer(graph: grimp.ImportGraph) -> None:
    unplaced = sorted(m for m in graph.modules if _layer(m) is None)
    assert not unplaced, f"modules missing from LAYERS: {unplaced}"


def test_imports_point_down_the_layers(graph: grimp.ImportGraph) -> None:
    """No direct import (module level or inside a function) goes to a higher layer."""
    wrong = []
    for module in sorted(graph.modules):
        source = _layer(module)
        if source is None:
            continue
        for imported in graph.find_modules_directly_imported_by(module):
            target = _layer(imported)
            if target is None or _top(imported) == _top(module):
                continue
            if target < source:
                wrong.append(f"{module} -> {imported}")
    assert not wrong, "imports against the layering:\n" + "\n".join(wrong)


@pytest.mark.parametrize(
    ("importer", "imported"),
    [
        ("rotorfault.simulation", "rotorfault.control"),
        ("rotorfault.allocation", "rotorfault.control"),
        ("rotorfault.control", "rotorfault.papers"),
        ("rotorfault.control", "rotorfault.cli"),
        ("rotorfault.papers", "rotorfault.cli"),
        ("rotorfault.scenario", "rotorfault.papers"),
    ],
)
def test_forbidden_dependencies(graph: grimp.ImportGraph, importer: str, imported: str) -> None:
    """The named rules of the layering, also indirectly (any chain of imports)."""
    chain = graph.find_shortest_chain(importer=importer, imported=imported, as_packages=True)
    assert chain is None, " -> ".join(chain or ())


def test_only_the_entry_points_import_cli(graph: grimp.ImportGraph) -> None:
    importers = {m for m in graph.find_modules_that_directly_import("rotorfault.cli")}
    assert importers <= {"rotorfault.__main__"}, importers


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
