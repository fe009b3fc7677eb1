"""The one registry of Rust controllers (``controller_registry!`` in the bindings, exposed as
``rotorfault._rfcore.CONTROLLERS``): declared once, everything else derived from it and checked
here, and a toy controller added the documented way (``docs/adding-a-controller.md``) shows up in
every derived place."""

from __future__ import annotations

import re
import typing
from pathlib import Path

import numpy as np
import pytest

import rotorfault as rf
from rotorfault import _rfcore, _typing
from rotorfault.control import registry

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "adding-a-controller.md"


def test_the_bindings_declare_the_list_once_and_expose_it() -> None:
    """The source's one declaration is what the running extension exposes, in order, and the
    batch type check reads exactly those classes."""
    declared = registry.parse_source((ROOT / registry.SOURCE).read_text(encoding="utf-8"))
    assert declared == registry.entries()
    assert [name for name, _ in _rfcore.CONTROLLERS] == [e.name for e in declared]
    assert _typing.core_controller_types() == tuple(e.core for e in declared)
    assert rf.flight.simulator.CORE_TYPES == _typing.core_controller_types()


@pytest.mark.parametrize("path", sorted(registry.render()))
def test_every_derived_block_matches_the_registry(path: str) -> None:
    """``_typing.py``, ``_rfcore.pyi`` and the docs hold the block ``python -m
    rotorfault.control.registry`` renders from the registry (paste it after adding a controller)."""
    text = (ROOT / path).read_text(encoding="utf-8")
    assert registry.derived_block(text) == registry.render()[path]


def test_the_static_types_name_every_registered_controller() -> None:
    entries = registry.entries()
    assert typing.get_args(_typing.CoreControllerName) == tuple(e.name for e in entries)
    assert typing.get_args(_typing.CoreController) == tuple(e.core for e in entries)


def test_every_controller_has_one_name_in_rust_python_and_the_registry() -> None:
    """The bindings' class, the public Python class and the kebab-case registry name agree, and
    the public class hands over the registered core class."""
    for entry in registry.entries():
        assert entry.name == registry.kebab(entry.class_name)
        assert entry.core.__name__ == entry.class_name and entry.core.__module__ == "rotorfault._rfcore"
        public = entry.public
        assert public.__name__ == entry.class_name and callable(getattr(public, "core", None)), entry
        assert public.__module__.startswith("rotorfault.control."), entry


def test_the_recipe_was_followed_for_every_registered_controller() -> None:
    """``docs/adding-a-controller.md`` says where each step of the recipe lives for every
    registered controller: every file exists and names the controller."""
    text = DOC.read_text(encoding="utf-8")
    rows = {m.group(1): m.group(2) for m in re.finditer(r"^\| `(\w+)` \| (`crates/rfcore/src.*)\|$", text, re.M)}
    assert set(rows) == {e.class_name for e in registry.entries()}
    for class_name, cells in rows.items():
        paths = re.findall(r"`([^`]+)`", cells)
        assert len(paths) == 5, (class_name, paths)
        for path in paths:
            body = (ROOT / path).read_text(encoding="utf-8")
            assert class_name in body or registry.kebab(class_name) in body, f"{path} does not name {class_name}"
        assert f"impl crate::control::class::ControllerClass for Py{class_name}" in (ROOT / paths[1]).read_text() or (
            f"impl ControllerClass for Py{class_name}" in (ROOT / paths[1]).read_text()
        ), f"{paths[1]}: no ControllerClass impl for Py{class_name}"
    stub = (ROOT / "python" / "rotorfault" / "_rfcore.pyi").read_text(encoding="utf-8")
    for entry in registry.entries():
        assert f"class {entry.class_name}:" in stub, f"_rfcore.pyi: no stub for {entry.class_name}"


def test_a_batch_refuses_what_the_registry_does_not_list() -> None:
    """The batch check and its message come from the registry: a callable is refused, naming
    the registered classes."""
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    with pytest.raises(TypeError, match="Python callables cannot run in a batch"):
        rf.simulate_batch(sim, [rf.State()], 0.1, controllers=[lambda t, x: np.zeros(4)])
    with pytest.raises(TypeError, match=", ".join(e.class_name for e in registry.entries())):
        sim.run(rf.State(), 0.1, controller=object())


# -- a toy controller, added the documented way -----------------------------------------------

TOY = 'Toy(PyToy) = "toy",'


def _with_toy(source: str) -> str:
    """Step 2 of the recipe: one line in ``controller_registry!`` (after the last entry)."""
    block = re.search(r"^controller_registry! \{\n(.*?)^\}", source, re.S | re.M)
    assert block is not None
    return source[: block.end(1)] + f"    {TOY}\n" + source[block.end(1) :]


class _ToyCore:
    """Stands for the extension's ``Toy`` class (what step 2 would compile)."""


def test_a_toy_controller_added_the_documented_way_is_found_everywhere(monkeypatch: pytest.MonkeyPatch) -> None:
    source = (ROOT / registry.SOURCE).read_text(encoding="utf-8")
    declared = registry.parse_source(_with_toy(source))
    assert declared[-1] == registry.Entry("toy", "Toy") and declared[:-1] == registry.entries()
    # Step 3: the derived blocks rendered from the registry name the toy.
    blocks = registry.render(declared)
    assert "| _rfcore.Toy" in blocks["python/rotorfault/_typing.py"] and '"toy",' in blocks["python/rotorfault/_typing.py"]
    assert blocks["python/rotorfault/_rfcore.pyi"].endswith("| Toy\n# </controller-registry>")
    assert "| `toy` | `rotorfault._rfcore.Toy` | `rotorfault.control.Toy` |" in blocks["docs/adding-a-controller.md"]
    # ... and until they are pasted, the check of every derived block fails on each file.
    for path, block in blocks.items():
        assert registry.derived_block((ROOT / path).read_text(encoding="utf-8")) != block
    # At run time the extension would expose it: the batch check and its message take it up.
    monkeypatch.setattr(_rfcore, "CONTROLLERS", (*_rfcore.CONTROLLERS, ("toy", _ToyCore)))
    monkeypatch.setattr(_rfcore, "Toy", _ToyCore, raising=False)
    assert _ToyCore in _typing.core_controller_types()
    assert registry.entries()[-1] == registry.Entry("toy", "_ToyCore")
    with pytest.raises(TypeError, match="_ToyCore"):
        rf.Simulator(rf.Airframe.preset("quad-x")).run(rf.State(), 0.1, controller=object())


def test_a_registry_line_that_breaks_the_naming_rule_is_refused() -> None:
    source = (ROOT / registry.SOURCE).read_text(encoding="utf-8")
    bad = source.replace('Lti(PyLti) = "lti",', 'Lti(PyLti) = "linear-time-invariant",')
    with pytest.raises(ValueError, match="expected Lti"):
        registry.parse_source(bad)
