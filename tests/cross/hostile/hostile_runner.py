"""How the hostile-input harness makes each call: under a time limit, in rounds of Hypothesis
examples until the profile's example count or the target's time budget is spent, counting calls.

- In CI (Hypothesis' default profile, or any profile of fewer than 1,000 examples) each target
  makes :data:`CI_EXAMPLES` calls, derandomized (the same calls on every run, no database).
  ``--hypothesis-profile=long`` (registered in ``tests/conftest.py``; the pre-release run,
  DEVELOPERS.md) runs rounds of random examples until ``max_examples`` calls or
  ``ROTORFAULT_HOSTILE_SECONDS`` seconds per target (default 30), so an hour covers every target.
- Each call must return or raise within :data:`CALL_LIMIT_S` of CPU time (the process's, every
  thread's) and :data:`CALL_WALL_LIMIT_S` of wall time: a timer (SIGPROF, SIGALRM) raises
  :class:`CallTimeout` in the call (long Rust calls run Python's signal handlers as they poll for
  Ctrl-C), so Hypothesis shrinks a slow call like any failure, each retry under its own timers.
  A busy machine stretches wall time, not CPU time: a campaign of 0.5 s of CPU took 35 s at
  ``nice 19`` under a load of 24, and a wall-time limit of 60 s failed such a call once and not on
  Hypothesis' replay (a flaky failure of the long run). A spinning hang uses CPU and meets the
  first limit; a blocked one (waiting, no CPU) the second. The test's ``pytest-timeout`` (thread
  method: it leaves the signals to the harness) is the last resort.
- ``ROTORFAULT_HOSTILE_LOG=path`` appends one JSON line per target: calls made, refusals, results
  and each round's Hypothesis seed. A failure is written there before it propagates, so it can be
  replayed when the run's output is lost or Hypothesis cannot reproduce it (a flaky failure): a
  ``"failure"`` line when a call first fails (the call in full, the error and its traceback) and,
  when the round ends, one with the seed, the shrunk call and Hypothesis' ``@reproduce_failure``
  blob. ``ROTORFAULT_HOSTILE_SEED=seed`` runs the first round of the long profile with that seed
  (``ROTORFAULT_HOSTILE_SEED=<seed> pytest ... --hypothesis-profile=long -k <target>``).
"""

from __future__ import annotations

import contextlib
import json
import os
import random
import re
import signal
import sys
import threading
import time
import traceback
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from hostile_targets import FIELD_WORDS, Call, Target
from hypothesis import HealthCheck, Phase, given, seed, settings

#: A call that uses more CPU time than this fails: the harness's calls are small (a few rotors,
#: runs of a second), so this is a hang, not slow work.
CALL_LIMIT_S = 60.0
#: A call that waits longer than this (wall time) fails too: a hang that blocks without using the
#: CPU. Ten times the CPU limit, so that a machine loaded tenfold does not fail a short call.
CALL_WALL_LIMIT_S = 10 * CALL_LIMIT_S


class CallTimeout(Exception):
    """Raised in a call that outlives :data:`CALL_LIMIT_S` of CPU or :data:`CALL_WALL_LIMIT_S`."""


def _expire(signum: int, frame: object) -> None:
    raise CallTimeout("CPU time" if signum == signal.SIGPROF else "wall time")


@contextlib.contextmanager
def time_limit(cpu_seconds: float, wall_seconds: float | None = None) -> Iterator[None]:
    """Raises :class:`CallTimeout` in the main thread after ``cpu_seconds`` of the process's CPU
    time (all threads: ITIMER_PROF) or ``wall_seconds`` (default ten times as long) of wall time."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    wall = 10 * cpu_seconds if wall_seconds is None else wall_seconds
    previous = {sig: signal.signal(sig, _expire) for sig in (signal.SIGPROF, signal.SIGALRM)}
    signal.setitimer(signal.ITIMER_PROF, cpu_seconds)
    signal.setitimer(signal.ITIMER_REAL, wall)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0.0)
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
#: Calls per target in CI.
CI_EXAMPLES = 6
#: A profile with at least this many examples is a long run.
LONG_EXAMPLES = 1000
#: Examples per round in the long profile (each round is one Hypothesis run with its own seed).
ROUND_EXAMPLES = 50
#: The pytest-timeout of one target's test: its budget, then room for Hypothesis to shrink a call
#: that timed out (each retry stopped by its timers).
TEST_TIMEOUT_S = int(float(os.environ.get("ROTORFAULT_HOSTILE_SECONDS", "30")) + 2 * CALL_WALL_LIMIT_S + 20 * CALL_LIMIT_S)

#: A refusal names its field: ``field: rule`` (the project's form) or a word the call was given.
#: ``field: rule``: one or more field names (``a.b[2]``, ``quad_params['mass']``, a file's path),
#: comma-separated, perhaps with a parenthesis (``position_m[5][2] (rotor 6): ...``), then a colon.
_FIELD_FIRST = re.compile(r"^[^\s:,]+(?:, [^\s:,]+)*(?: \([^)]*\))?:")


def names_a_field(message: str, call: Call) -> bool:
    if _FIELD_FIRST.match(message):
        return True
    words = call.words | FIELD_WORDS | set(call.kwargs)
    return any(word and word in message for word in words)


#: The longest repr of a failing call written to the log (numpy already summarises big arrays).
LOGGED_REPR_CHARS = 20_000


def full_repr(call: Call) -> str:
    """The call with every argument's repr (``Call.__repr__`` cuts each at 300 characters)."""
    name = getattr(call.fn, "__qualname__", repr(call.fn))
    shown = [repr(a) for a in call.args] + [f"{k}={v!r}" for k, v in call.kwargs.items()]
    text = f"{name}({', '.join(shown)})"
    return text if len(text) <= LOGGED_REPR_CHARS else text[:LOGGED_REPR_CHARS] + "..."


def log_line(entry: dict[str, object]) -> None:
    """One JSON line to ``ROTORFAULT_HOSTILE_LOG`` (if set), flushed at once: a run that is killed
    later keeps it."""
    path = os.environ.get("ROTORFAULT_HOSTILE_LOG")
    if path:
        stamp = {"utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "load_1min": round(os.getloadavg()[0], 1)}
        with open(path, "a", encoding="utf-8") as handle:
            handle.write(json.dumps({**entry, **stamp}, default=repr) + "\n")


@dataclass
class Round:
    """One Hypothesis run of a target: its seed and the calls that failed in it (the first as
    drawn, the last as shrunk)."""

    target: str
    seed: int | None
    examples: int
    failed_calls: int = 0
    first: dict[str, object] | None = None
    last: dict[str, object] | None = None

    def failed(self, call: Call, exc: BaseException) -> None:
        entry: dict[str, object] = {
            "call": full_repr(call), "error": f"{type(exc).__name__}: {exc}",
            "traceback": "".join(traceback.format_exception(type(exc), exc, exc.__traceback__)),
        }
        self.failed_calls += 1
        self.last = entry
        if self.first is None:
            self.first = entry
            # Written before the error propagates: kept even if the run is killed while shrinking.
            log_line({"target": self.target, "event": "failure", "seed": self.seed, "examples": self.examples, **entry})

    def ended_with(self, exc: BaseException) -> None:
        notes = list(getattr(exc, "__notes__", ()))
        log_line({
            "target": self.target, "event": "round-failed", "seed": self.seed, "examples": self.examples,
            "failed_calls": self.failed_calls, "error": f"{type(exc).__name__}: {exc}", "notes": notes,
            "reproduce_failure": next((n for n in notes if "@reproduce_failure" in n), None),
            "first_call": None if self.first is None else self.first["call"],
            "shrunk_call": None if self.last is None else self.last["call"],
            "shrunk_traceback": None if self.last is None else self.last["traceback"],
            "replay": None if self.seed is None else f"ROTORFAULT_HOSTILE_SEED={self.seed} (first round, {self.examples} examples)",
        })


def call_once(name: str, target: Target, call: Call, counts: dict[str, int], round_: Round | None = None) -> None:
    try:
        _call_once(name, target, call, counts)
    except BaseException as exc:
        if round_ is not None:
            round_.failed(call, exc)
        raise


def _call_once(name: str, target: Target, call: Call, counts: dict[str, int]) -> None:
    try:
        with warnings.catch_warnings(), time_limit(CALL_LIMIT_S, CALL_WALL_LIMIT_S):
            warnings.simplefilter("error")
            result = call.fn(*call.args, **call.kwargs)
    except CallTimeout as exc:
        limit = CALL_LIMIT_S if str(exc) == "CPU time" else CALL_WALL_LIMIT_S
        raise AssertionError(f"{name}: {call!r} did not return within {limit:.0f} s of {exc}") from None
    except KeyboardInterrupt:  # never: only the user's Ctrl-C may raise it
        raise AssertionError(f"{name}: KeyboardInterrupt from {call!r}") from None
    except (ValueError, TypeError, OSError) as exc:
        message = " ".join([str(exc), *getattr(exc, "__notes__", ())])
        assert message.strip(), f"{name}: {type(exc).__name__} without a message from {call!r}"
        assert names_a_field(message, call), f"{name}: {type(exc).__name__} names no field: {message!r}"
        counts["refused"] += 1
    else:
        target.check(result, call)
        counts["returned"] += 1
    finally:
        counts["calls"] += 1


def run_target(name: str, target: Target, profile: settings | None = None) -> dict[str, int]:
    """Runs the target's calls under ``profile`` (default: the loaded one); returns the counts."""
    profile = settings.default if profile is None else profile
    long = profile.max_examples >= LONG_EXAMPLES
    total = profile.max_examples if long else CI_EXAMPLES
    budget_s = float(os.environ.get("ROTORFAULT_HOSTILE_SECONDS", "30"))
    replay = os.environ.get("ROTORFAULT_HOSTILE_SEED")
    counts = {"calls": 0, "refused": 0, "returned": 0}
    seeds: list[int] = []
    started = time.monotonic()
    try:
        regression = Round(name, None, len(target.examples))
        for case in target.examples:
            call_once(name, target, case, counts, regression)
        while counts["calls"] < total:
            examples = min(ROUND_EXAMPLES, total - counts["calls"])
            # The long profile's rounds each get a seed of their own, logged, so any round can be
            # replayed (ROTORFAULT_HOSTILE_SEED); CI's rounds are derandomized.
            round_seed = (int(replay) if replay and not seeds else random.SystemRandom().getrandbits(64)) if long else None
            current = Round(name, round_seed, examples)

            # No "explain" phase: it imports libcst, whose DeprecationWarning is an error here.
            @settings(
                profile, max_examples=examples, deadline=None, database=None, derandomize=not long, print_blob=True,
                phases=[Phase.explicit, Phase.reuse, Phase.generate, Phase.target, Phase.shrink],
                suppress_health_check=list(HealthCheck),
            )
            @given(call=target.calls)
            def one(call: Call) -> None:
                call_once(name, target, call, counts, current)

            if round_seed is not None:
                one = seed(round_seed)(one)
                seeds.append(round_seed)
            before = counts["calls"]
            try:
                one()
            except BaseException as exc:
                current.ended_with(exc)
                raise
            if counts["calls"] == before or time.monotonic() - started > budget_s:
                break
    finally:
        seconds = round(time.monotonic() - started, 1)
        log_line({"target": name, **counts, "seconds": seconds, "passed": sys.exc_info()[0] is None, "seeds": seeds})
    return counts
