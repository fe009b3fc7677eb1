"""A Python result that holds the core's result object in its one slot (``_core``) and reads
every field through it (issue 26: types cross the boundary once; values are validated once, in
Rust). :class:`CoreResult` gives such a class what the dataclass it replaced had: a repr, equality
and a hash over its fields (``FIELDS``, from :class:`FieldsResult`, which a frozen dataclass that
reads some fields through an object it holds uses too), and refuses new attributes (it was frozen)."""

from __future__ import annotations

from typing import Any, ClassVar


class FieldsResult:
    """A result whose repr, equality and hash are over its ``FIELDS`` (in the order the repr
    shows them), each read by name: what the dataclass it replaced had, also where some fields
    are read through an object it holds."""

    __slots__ = ()
    FIELDS: ClassVar[tuple[str, ...]] = ()

    def _values(self) -> tuple[Any, ...]:
        return tuple(getattr(self, name) for name in self.FIELDS)

    def _as_dict(self) -> dict[str, Any]:
        """The fields by name, in order (what ``dataclasses.asdict`` gave the dataclass)."""
        return {name: getattr(self, name) for name in self.FIELDS}

    def __repr__(self) -> str:
        fields = ", ".join(f"{name}={getattr(self, name)!r}" for name in self.FIELDS)
        return f"{type(self).__qualname__}({fields})"

    def __eq__(self, other: object) -> bool:
        if other.__class__ is self.__class__:
            return self._values() == other._values()
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self._values())


class CoreResult(FieldsResult):
    """Base of a Python result over a core result (``_core``); subclasses name their ``FIELDS``
    (in the order the repr shows them) and read each through ``_core``."""

    __slots__ = ("_core",)
    _core: Any

    @classmethod
    def _from_core(cls, core: Any) -> Any:
        """The result over ``core`` (no copy, no second validation)."""
        out = object.__new__(cls)
        out._core = core
        return out
