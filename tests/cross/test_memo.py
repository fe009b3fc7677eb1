"""``_util.memo.computed_once``: a design cache shared by threads computes each key once, even
when threads ask for it together (``functools.lru_cache`` computes it in each of them: the
deciding campaign's two chunk threads designed the same relaxed hover twice), and does not keep
exceptions."""

from __future__ import annotations

import threading
import time

import pytest

from rotorfault._util.memo import computed_once


def test_threads_asking_together_compute_each_key_once() -> None:
    calls: list[int] = []
    started = threading.Event()
    release = threading.Event()

    @computed_once
    def slow_square(x: int) -> int:
        calls.append(x)
        started.set()
        release.wait(5.0)  # hold the first computation until every thread has asked
        return x * x

    results: list[int] = []
    threads = [threading.Thread(target=lambda: results.append(slow_square(3))) for _ in range(4)]
    threads[0].start()
    assert started.wait(5.0)
    for t in threads[1:]:
        t.start()
    time.sleep(0.2)  # let them reach the key (with functools.lru_cache each would be computing it now)
    release.set()
    for t in threads:
        t.join(5.0)
    assert results == [9, 9, 9, 9] and calls == [3]
    assert slow_square(4) == 16 and calls == [3, 4]


def test_an_exception_is_not_kept() -> None:
    calls: list[int] = []

    @computed_once
    def refuses_once(x: int) -> int:
        calls.append(x)
        if len(calls) == 1:
            raise ValueError("x: refused the first time")
        return x

    with pytest.raises(ValueError, match="^x: "):
        refuses_once(1)
    assert refuses_once(1) == 1 and refuses_once(1) == 1 and calls == [1, 1]
