"""The public objects of the package's rooms, walked once for the tests that check them all
(``tests/cross/test_docs.py``: documented with units; ``tests/cross/test_examples.py``: an example
that runs)."""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Iterable
from typing import Any


def public_callables(rooms: Iterable[str]) -> list[tuple[str, str, Any]]:
    """(room, name, object) for every function and class in a room's ``__all__``, each object once
    (the first room that lists it)."""
    seen: set[int] = set()
    found = []
    for room in rooms:
        module = importlib.import_module(room)
        for name in module.__all__:
            obj = getattr(module, name)
            if inspect.ismodule(obj) or not callable(obj) or id(obj) in seen:
                continue
            seen.add(id(obj))
            found.append((room, name, obj))
    return found
