"""griffe extension (mkdocs.yml): the docstrings' mentions of other API objects become links.

The docstrings are written for ``help()`` as well as for the site, so they name objects as
Sphinx roles (``:func:`hover_trim```, ``:class:`~rotorfault.control.LinearModel```) or as code
(````Allocator````). On the site each mention that resolves, in the scope of the object whose
docstring it is in, to a function or class the API pages document (docs/pages/api/*.md: their
``:::`` directives) becomes an mkdocstrings cross-reference to that object's heading, which
``mkdocs build --strict`` checks; a mention of anything else (a private helper, a parameter)
stays code. Code blocks (indented lines: doctests, literal blocks) are left as they are.
"""

from __future__ import annotations

import importlib
import inspect
import re
import sys
from pathlib import Path
from typing import Any

import griffe

#: The API pages: each ``::: path`` directive documents that object, and a module's ``__all__``
#: under it unless its options say ``members: false``.
API_PAGES = Path(__file__).resolve().parent / "pages" / "api"
_ROLE = re.compile(r":(?:class|func|meth|data|attr|obj|exc):`(~?)([A-Za-z_][\w.]*)`")
_MODULE_ROLE = re.compile(r":mod:`(~?)([A-Za-z_][\w.]*)`")
_CODE = re.compile(r"(?<![`\w])``([A-Za-z_][\w.]*)(\(\))?``(?!`)")


def defining_path(obj: Any) -> str | None:
    module, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    return f"{module}.{qualname}" if module and qualname else None


def documented_paths() -> dict[str, str]:
    """Each documented module (by its path) and function or class (by the path it is defined
    at), mapped to the path of its heading on the API pages: its own ``:::`` directive, else the first room that lists it (not
    under a name its room's submodule shadows, ``rotorfault.analysis.acai``: such a function has
    its own directive, ``::: rotorfault.analysis.acai.acai``)."""
    directives = []
    for page in sorted(API_PAGES.glob("*.md")):
        directives += re.findall(r"^::: ([\w.]+)\n((?:[ \t]+.*\n)*)", page.read_text(encoding="utf-8"), re.MULTILINE)
    documented: dict[str, str] = {}
    rooms = []
    for target, options in directives:
        obj = _lookup(target) or importlib.import_module(target)
        if inspect.ismodule(obj):
            documented.setdefault(target, target)
        if not inspect.ismodule(obj):
            if path := defining_path(obj):
                documented.setdefault(path, target)
        elif not re.search(r"members:\s*false", options):
            rooms.append((target, obj))
    for target, room in rooms:
        for name in getattr(room, "__all__", ()):
            member = getattr(room, name, None)
            shadowed = f"{target}.{name}" in sys.modules
            if (inspect.isclass(member) or inspect.isfunction(member)) and not shadowed and (path := defining_path(member)):
                documented.setdefault(path, f"{target}.{name}")
    return documented


class CrossReferences(griffe.Extension):
    def __init__(self) -> None:
        super().__init__()
        self.documented = documented_paths()

    def resolve(self, name: str, module_path: str, class_path: str | None) -> str | None:
        """The API-page heading of the documented object ``name`` means in that scope, or None."""
        scopes = [f"{class_path}.{name}"] if class_path else []
        scopes += [f"{module_path}.{name}", f"rotorfault.{name}"]
        if name.startswith("rotorfault."):
            scopes.append(name)
        for candidate in scopes:
            obj = _lookup(candidate)
            if obj is None:
                continue
            if inspect.isclass(obj) or inspect.isfunction(obj):
                return self.documented.get(defining_path(obj) or "")
            # A method of a documented class: its heading sits under the class's.
            owner, _, member = candidate.rpartition(".")
            cls = _lookup(owner)
            if inspect.isclass(cls) and callable(obj) and (heading := self.documented.get(defining_path(cls) or "")):
                return f"{heading}.{member}"
            return None
        return None

    def link_text(self, text: str, module_path: str, class_path: str | None) -> str:
        out = []
        for line in text.split("\n"):
            if line.startswith("    "):
                out.append(line)
                continue

            def role(match: re.Match[str]) -> str:
                short, name = match.group(1), match.group(2)
                target = self.resolve(name, module_path, class_path)
                shown = name.rsplit(".", 1)[-1] if short else name
                return f"[`{shown}`][{target}]" if target else f"`{shown}`"

            def code(match: re.Match[str]) -> str:
                target = self.resolve(match.group(1), module_path, class_path)
                return f"[`{match.group(1)}{match.group(2) or ''}`][{target}]" if target else match.group(0)

            def module(match: re.Match[str]) -> str:
                short, name = match.group(1), match.group(2)
                target = name if name in self.documented else None
                shown = name.rsplit(".", 1)[-1] if short else name
                return f"[`{shown}`][{target}]" if target else f"`{shown}`"

            out.append(_CODE.sub(code, _MODULE_ROLE.sub(module, _ROLE.sub(role, line))))
        return "\n".join(out)

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        for obj in _walk(pkg):
            if obj.docstring is None:
                continue
            module_path = obj.module.path
            class_path = obj.path if obj.is_class else (obj.parent.path if obj.parent is not None and obj.parent.is_class else None)
            obj.docstring.value = self.link_text(obj.docstring.value, module_path, class_path)


def _lookup(dotted: str) -> Any:
    """The object at ``dotted`` (an imported module's path then attributes), or None."""
    parts = dotted.split(".")
    for split in range(len(parts), 0, -1):
        # Only modules already imported (by the rooms): importing on a guess could run a
        # module's side effects (``rotorfault.__main__`` runs the CLI).
        obj: Any = sys.modules.get(".".join(parts[:split]))
        if obj is None:
            continue
        for attribute in parts[split:]:
            obj = getattr(obj, attribute, None)
            if obj is None:
                return None
        return obj
    return None


def _walk(obj: griffe.Object) -> Any:
    yield obj
    for member in obj.members.values():
        if not member.is_alias:
            yield from _walk(member)  # type: ignore[arg-type]
