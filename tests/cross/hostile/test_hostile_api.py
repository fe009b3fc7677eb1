"""The hostile-input harness over the public API (issue 27): every public callable of ``rotorfault``
and of its rooms (their ``__all__``) has a strategy of hostile calls (``hostile_targets.py``), or is
a result type covered through the call that makes it, or is a Protocol; a new public callable in
none of these fails :func:`test_every_public_callable_has_a_strategy`, so new API cannot escape.

Each call must raise ``ValueError``/``TypeError``/``OSError`` naming a field, or return a result
that passes its own checks, within a time limit (``hostile_runner.py``); ``KeyboardInterrupt``,
any other exception, a NaN or a hang fails. CI runs a few derandomized calls per target; the
pre-release run is ``--hypothesis-profile=long`` (DEVELOPERS.md)."""

from __future__ import annotations

import importlib
import inspect
import types

import pytest
from hostile_runner import TEST_TIMEOUT_S, CallTimeout, run_target, time_limit
from hostile_targets import NOT_CALLED, PRODUCED_BY, TARGETS

ROOMS = ("rotorfault", "rotorfault.analysis", "rotorfault.allocation", "rotorfault.control", "rotorfault.flight", "rotorfault.studies",
         "rotorfault.papers", "rotorfault.plotting")


def public_callables() -> dict[str, object]:
    found: dict[str, object] = {}
    for room in ROOMS:
        module = importlib.import_module(room)
        for name in getattr(module, "__all__", ()):
            value = getattr(module, name)
            if callable(value) and not isinstance(value, types.ModuleType):
                found.setdefault(name, value)
    return found


def test_every_public_callable_has_a_strategy() -> None:
    missing = sorted(name for name in public_callables() if name not in TARGETS and name not in PRODUCED_BY and name not in NOT_CALLED)
    assert missing == [], f"public callables without a hostile strategy (add one to tests/cross/hostile/hostile_targets.py): {missing}"
    for result_type, producer in PRODUCED_BY.items():
        assert producer in TARGETS, (result_type, producer)
    for name, value in public_callables().items():
        if name in NOT_CALLED:
            assert inspect.isclass(value) and getattr(value, "_is_protocol", False), name


def test_every_airframe_reader_has_a_strategy() -> None:
    """The airframe's public readers and conversions are targets too (``from_toml`` and ``load``
    read files: the CLI harness hands them TOML and PX4 files through ``--airframe``)."""
    readers = {f"Airframe.{n}" for n in ("from_toml_str", "from_rotorpy", "with_parameters", "with_efficiency", "to_px4_params")}
    assert readers <= set(TARGETS), sorted(readers - set(TARGETS))


@pytest.mark.timeout(120, method="thread")
def test_the_call_limit_stops_a_long_rust_call() -> None:
    """The harness's alarm reaches into the core (the bindings run Python's signal handlers as
    they poll for Ctrl-C): a call of minutes of work stops with CallTimeout, so a slow call is a
    failure Hypothesis can shrink instead of a hang."""
    import numpy as np

    import rotorfault as rf

    m = 52
    ring = rf.Airframe(np.arange(m) * 2 * np.pi / m, [0.3] * m, [1, -1] * (m // 2), [5.0] * m, 2.0, [0.05, 0.05, 0.09], 0.02)
    with pytest.raises(CallTimeout), time_limit(1.0):
        rf.acai_batch(ring, np.ones((200_000, m)))  # about 1 ms each: minutes of work


@pytest.mark.timeout(60, method="thread")
def test_the_call_limit_counts_cpu_time_and_waiting_separately() -> None:
    """A call that waits uses no CPU: a starved machine (the long run's flaky failure: a 0.5 s
    campaign took over 60 s of wall time at nice 10) cannot fail it on the CPU limit; a call that
    blocks still meets the wall-time limit."""
    import time

    with time_limit(0.3, 30.0):
        time.sleep(1.0)  # more wall time than the CPU limit, no CPU
    with pytest.raises(CallTimeout, match="wall time"), time_limit(30.0, 0.3):
        time.sleep(5.0)


@pytest.mark.timeout(TEST_TIMEOUT_S, method="thread")
@pytest.mark.parametrize("name", sorted(TARGETS))
def test_hostile_calls(name: str) -> None:
    counts = run_target(name, TARGETS[name])
    assert counts["calls"] > 0


def _fails_above_500(n: int) -> int:
    if n > 500:
        raise RuntimeError(f"n = {n}")
    return n


def test_a_failure_is_logged_with_what_replays_it(tmp_path, monkeypatch) -> None:
    """A long run's failure is in the log before it propagates (the call in full, its traceback,
    the round's seed and Hypothesis' blob), and the logged seed replays the same first call: a
    failure that Hypothesis cannot reproduce, or whose output is lost, is not lost with it."""
    import json

    from hypothesis import settings
    from hypothesis import strategies as st

    from hostile_runner import LONG_EXAMPLES
    from hostile_targets import Call, Target

    target = Target(st.integers(0, 10**6).map(lambda n: Call(_fails_above_500, (n,))))
    long = settings(max_examples=LONG_EXAMPLES, deadline=None)
    log = tmp_path / "hostile.jsonl"
    monkeypatch.setenv("ROTORFAULT_HOSTILE_LOG", str(log))

    def run() -> list[dict[str, object]]:
        log.write_text("")
        with pytest.raises(RuntimeError):
            run_target("toy", target, long)
        return [json.loads(line) for line in log.read_text().splitlines()]

    first, ended, summary = run()
    assert first["event"] == "failure" and first["call"].startswith("_fails_above_500(") and "RuntimeError: n = " in first["traceback"]
    assert ended["event"] == "round-failed" and ended["seed"] == first["seed"] and ended["first_call"] == first["call"]
    assert ended["shrunk_call"] == "_fails_above_500(501)"  # shrunk to the boundary
    assert "@reproduce_failure(" in ended["reproduce_failure"]
    assert summary["passed"] is False and summary["seeds"] == [first["seed"]]
    monkeypatch.setenv("ROTORFAULT_HOSTILE_SEED", str(first["seed"]))
    replayed = run()
    assert replayed[0]["call"] == first["call"] and replayed[0]["seed"] == first["seed"]
