"""The one registry of the Rust controllers, as Python sees it.

The list is declared once, in the bindings (``controller_registry!`` in
``crates/rfcore-py/src/control/mod.rs``), and exposed as ``rotorfault._rfcore.CONTROLLERS``:
``(name, class)`` pairs, the name being the class name in kebab case. Everything else is derived
from it: the simulator's batch type check and its error message read it at run time
(:func:`rotorfault._typing.core_controller_types`); the static types of ``rotorfault._typing``
(``CoreController``, ``CoreControllerName``) and of ``_rfcore.pyi`` and the table of
``docs/adding-a-controller.md`` are rendered from it (:func:`render`, ``python -m
rotorfault.control.registry``) and ``tests/control/test_registry.py`` checks each one against it.
Each entry's public Python class has the core class's name, in :mod:`rotorfault.control`.
"""

from __future__ import annotations

import re
from typing import NamedTuple

from .. import _rfcore

#: Where the registry is declared (repository path).
SOURCE = "crates/rfcore-py/src/control/mod.rs"
#: The markers around each derived block (``<controller-registry>`` ... ``</controller-registry>``).
BEGIN, END = "<controller-registry>", "</controller-registry>"


class Entry(NamedTuple):
    """One registered controller: its kebab-case ``name`` and the name of its class, the same in
    Rust (``_rfcore.<class_name>``) and in Python (``rotorfault.control.<class_name>``)."""

    name: str
    class_name: str

    @property
    def core(self) -> type:
        """The extension's class (what ``core(dt_s)`` returns)."""
        cls: type = getattr(_rfcore, self.class_name)
        return cls

    @property
    def public(self) -> type:
        """The public Python class (design in Python, ``core(dt_s)`` hands the Rust object over)."""
        import importlib

        cls: type = getattr(importlib.import_module("rotorfault.control"), self.class_name)
        return cls


def entries() -> tuple[Entry, ...]:
    """The registry as the running extension module declares it, in declaration order."""
    return tuple(Entry(name, cls.__name__) for name, cls in _rfcore.CONTROLLERS)


def kebab(class_name: str) -> str:
    """``"UniformPassiveFtc"`` -> ``"uniform-passive-ftc"``: the registry's naming rule."""
    return re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "-", class_name).lower()


_LINE = re.compile(r"^\s*(\w+)\((Py\w+)\)\s*=\s*\"([a-z0-9-]+)\",?\s*$")


def parse_source(text: str) -> tuple[Entry, ...]:
    """The entries of the ``controller_registry! { ... }`` invocation in the bindings' source
    ``text`` (one ``Variant(PyClass) = "name",`` per line). ``ValueError`` if a line breaks the
    rules: the variant is the class name, ``PyClass`` is ``Py`` + that name, the name its kebab case."""
    match = re.search(r"^controller_registry! \{\n(.*?)^\}", text, re.S | re.M)
    if match is None:
        raise ValueError(f"{SOURCE}: no controller_registry! {{ ... }} invocation")
    out = []
    for line in match.group(1).splitlines():
        if not line.strip() or line.strip().startswith("//"):
            continue
        m = _LINE.match(line)
        if m is None:
            raise ValueError(f"{SOURCE}: registry line {line.strip()!r} is not `Variant(PyClass) = \"name\",`")
        variant, py_class, name = m.groups()
        if py_class != f"Py{variant}" or name != kebab(variant):
            raise ValueError(f"{SOURCE}: {line.strip()!r}: expected {variant}(Py{variant}) = \"{kebab(variant)}\"")
        out.append(Entry(name, variant))
    return tuple(out)


def _block(lines: list[str], comment: str = "#") -> str:
    head = f"{comment} {BEGIN} derived from the registry of {SOURCE}"
    return "\n".join([head, *lines, f"{comment} {END}"])


def render_typing(registry: tuple[Entry, ...]) -> str:
    """The block of ``rotorfault/_typing.py``: the ``CoreController`` union and the
    ``CoreControllerName`` literal."""
    return _block(
        [
            "# (`python -m rotorfault.control.registry` prints this block; tests/control/test_registry.py checks it)",
            "#: The Rust controller objects the simulator's loop runs (all can run in a batch).",
            "CoreController: TypeAlias = (",
            *[f"    {'| ' if k else ''}_rfcore.{e.class_name}" for k, e in enumerate(registry)],
            ")",
            "#: Their names: each class name in kebab case (``rotorfault._rfcore.CONTROLLERS``).",
            "CoreControllerName: TypeAlias = Literal[",
            *[f'    "{e.name}",' for e in registry],
            "]",
        ]
    )


def render_stub(registry: tuple[Entry, ...]) -> str:
    """The block of ``rotorfault/_rfcore.pyi``: the union of the controller classes."""
    return _block(["_Controller = " + " | ".join(e.class_name for e in registry)])


def render_docs(registry: tuple[Entry, ...]) -> str:
    """The table of ``docs/adding-a-controller.md``: every registered controller, its Rust and
    Python classes."""
    rows = [f"| `{e.name}` | `rotorfault._rfcore.{e.class_name}` | `rotorfault.control.{e.class_name}` |" for e in registry]
    return "\n".join([
        f"<!-- {BEGIN} derived from the registry of {SOURCE} -->",
        "| name | Rust class (bindings) | Python class |",
        "|---|---|---|",
        *rows,
        f"<!-- {END} -->",
    ])


def render(registry: tuple[Entry, ...] | None = None) -> dict[str, str]:
    """Every derived block, by the file it belongs in (repository paths)."""
    reg = entries() if registry is None else registry
    return {
        "python/rotorfault/_typing.py": render_typing(reg),
        "python/rotorfault/_rfcore.pyi": render_stub(reg),
        "docs/adding-a-controller.md": render_docs(reg),
    }


def derived_block(text: str) -> str:
    """The block of a file's ``text`` between the marker lines (a ``#`` or ``<!--`` comment line
    holding ``<controller-registry>`` ... ``</controller-registry>``), markers included."""
    lines = text.splitlines()
    marker = [k for k, line in enumerate(lines) if line.lstrip().startswith(("#", "<!--")) and (BEGIN in line or END in line)]
    if len(marker) != 2:
        raise ValueError(f"expected one {BEGIN} ... {END} block, found {len(marker)} marker lines")
    return "\n".join(lines[marker[0] : marker[1] + 1])


if __name__ == "__main__":
    for path, block in render().items():
        print(f"== {path}\n{block}\n")


__all__ = ["BEGIN", "END", "SOURCE", "Entry", "derived_block", "entries", "kebab", "parse_source", "render"]
