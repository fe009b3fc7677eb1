"""The one way an old name keeps working for one release: it warns (``DeprecationWarning``,
naming the new name) and then does what the new name does. Used for moved modules, renamed
arguments, attributes and keys; ``tests/cross/test_deprecations.py`` checks every one. An old
call form whose answers cannot be kept (the rule behind it changed, so a warning followed by the
new rule would answer something else under the old name) is refused instead, with a
``TypeError`` naming the current signature (:func:`removed_call_form`)."""

from __future__ import annotations

import functools
import importlib
import inspect
import sys
import warnings
from typing import Any, Callable, TypeVar

_F = TypeVar("_F", bound=Callable[..., Any])


def warn(old: str, new: str, *, stacklevel: int = 3) -> None:
    """Warns that ``old`` is deprecated in favour of ``new`` (removed after one release)."""
    warnings.warn(f"{old} is deprecated and will be removed in the next release; use {new}", DeprecationWarning, stacklevel=stacklevel)


def removed_call_form(old_parameters: int, why: str, instead: str) -> Callable[[_F], _F]:
    """Refuses a call that does not fit the decorated function's signature with a ``TypeError``
    naming the signature (in place of Python's bare "missing arguments"); a call that fits the
    removed form (its first ``old_parameters`` parameters, and only those) is told ``why`` that
    form was removed and what to call ``instead``. The signature seen by ``inspect`` and the docs
    is the function's own."""

    def decorate(function: _F) -> _F:
        signature = inspect.signature(function)
        old_names = list(signature.parameters)[:old_parameters]
        name = function.__name__
        # The parameters as a caller writes them (annotations left to the docs).
        plain = signature.replace(parameters=[p.replace(annotation=inspect.Parameter.empty) for p in signature.parameters.values()],
                                  return_annotation=inspect.Signature.empty)

        @functools.wraps(function)
        def checked(*args: Any, **kwargs: Any) -> Any:
            try:
                signature.bind(*args, **kwargs)
            except TypeError as e:
                old = len(args) + len(kwargs) == old_parameters and set(kwargs) <= set(old_names[len(args):])
                told = (f"{name}({', '.join(old_names)}) was removed: {why}; call {name}{plain}" + (f" or {instead}" if instead else "")
                        if old else f"{name}{plain}: {e}")
                raise TypeError(told) from None
            return function(*args, **kwargs)

        return checked  # type: ignore[return-value]

    return decorate


def moved_module(old: str, new: str) -> None:
    """Makes the module ``old`` (being imported) the module ``new``: one object under both names,
    so every name, private ones included, resolves as before; warns once per import."""
    warn(f"module {old}", new, stacklevel=4)
    sys.modules[old] = importlib.import_module(new)


def renamed_keyword(function: str, old: str, new: str, value: Any, given: Any, default: Any) -> Any:
    """The value of keyword ``new`` when the caller passed the deprecated ``old`` instead (``value``
    is what ``old`` got; ``given`` what ``new`` got, ``default`` its default)."""
    warn(f"{function}({old}=...)", f"{function}({new}=...)", stacklevel=4)
    if given is not default:
        raise TypeError(f"{function}: give {new} or the deprecated {old}, not both")
    return value


def renamed_attribute(old: str, new: str) -> property:
    """A read-only property ``old`` that warns and returns attribute ``new`` (for a class body:
    ``acai_without_yaw = renamed_attribute("acai_without_yaw", "acai_give_up_yaw")``)."""

    def get(self: Any) -> Any:
        warn(f"{type(self).__name__}.{old}", f"{type(self).__name__}.{new}")
        return getattr(self, new)

    return property(get, doc=f"Deprecated name of :attr:`{new}`.")


class _DataclassFields:
    """``__dataclass_fields__`` of a settings class of the extension (``FIELDS``), so that
    ``dataclasses.replace(obj, ...)`` and ``dataclasses.fields(obj)`` keep working for one
    release: read from an object it warns (use ``obj.replace(...)`` and ``Class.FIELDS``)."""

    def __get__(self, obj: Any, cls: type) -> dict[str, Any]:
        import dataclasses

        if obj is not None:
            # A result made only by its function (no ``replace``) is pointed at its fields alone.
            instead = f"{cls.__name__}.replace(...) and {cls.__name__}.FIELDS" if hasattr(cls, "replace") else f"{cls.__name__}.FIELDS"
            warn(f"dataclasses.replace / dataclasses.fields on a {cls.__name__}", instead)
        out = {}
        for name in cls.FIELDS:  # type: ignore[attr-defined]
            f = dataclasses.field()
            f.name = name
            f.type = Any
            f._field_type = dataclasses._FIELD  # type: ignore[attr-defined]  # what dataclasses.fields() keeps
            out[name] = f
        return out


def dataclass_compat(cls: type) -> None:
    """Lets the dataclass functions keep working, with a warning, on ``cls``: a class of the
    extension that replaced a Python dataclass of the same name (issue 26: types cross the
    boundary once)."""
    setattr(cls, "__dataclass_fields__", _DataclassFields())
