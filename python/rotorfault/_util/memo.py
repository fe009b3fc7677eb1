"""A cache of designs that threads share: each key is computed once, however many threads ask for
it at the same time. ``functools.lru_cache`` computes a key again in every thread that misses it
while the first is still at work: the deciding campaign's two chunk threads (the local backend
keeps two chunks in flight) each designed the same relaxed hover, seconds apiece. Exceptions are
not cached (as ``lru_cache``); the cache grows with the keys asked for, so it is for key sets that
are bounded by construction (a vehicle table times a design schedule)."""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Hashable
from typing import Any, TypeVar

T = TypeVar("T")


def computed_once(function: Callable[..., T]) -> Callable[..., T]:
    """``function`` (positional, hashable arguments) cached: each argument tuple computed once."""
    values: dict[tuple[Hashable, ...], T] = {}
    in_progress: dict[tuple[Hashable, ...], threading.Lock] = {}
    guard = threading.Lock()

    @functools.wraps(function)
    def cached(*args: Any) -> T:
        with guard:
            if args in values:
                return values[args]
            lock = in_progress.setdefault(args, threading.Lock())
        with lock:
            with guard:
                if args in values:  # computed by the thread this one waited for
                    return values[args]
            value = function(*args)
            with guard:
                values[args] = value
                in_progress.pop(args, None)
            return value

    return cached
