"""Usage examples (issue 31): every public function and class of the rooms' ``__all__`` (and the
top-level ``rotorfault.__all__``) has an ``Examples:`` section in its own docstring, a doctest
that shows what the call prints, and every such example runs and prints what it shows.

Printed floats are compared to the precision they are written with (``1.1295`` matches any
``1.12945 <= x < 1.12955``, as pytest's ``NUMBER`` option), everything else exactly; the
examples round what they print, so the rule only absorbs the last digit's rounding. The examples
are small (each well under a second once the package and python-control are imported).
"""

from __future__ import annotations

import doctest
import inspect
import re
from typing import Any

import public_api
import pytest

#: The rooms whose ``__all__`` is the public API an example documents.
EXAMPLE_ROOMS = ("rotorfault", "rotorfault.analysis", "rotorfault.flight", "rotorfault.allocation",
                 "rotorfault.control", "rotorfault.studies", "rotorfault.papers")
#: Public callables excused from having an example, and why (each listed by name; a name that
#: gets an example, or leaves the API, must leave this table: a test checks). None now.
WITHOUT_EXAMPLE: dict[str, str] = {}
_FLOAT = re.compile(r"-?\d+\.\d+(?:[eE][-+]?\d+)?")
_EXAMPLES_HEADING = re.compile(r"^\s*Examples:\s*$", re.MULTILINE)


def public_objects() -> list[tuple[str, Any]]:
    """(where it is defined, object) for every function and class of the rooms' ``__all__``, each once."""
    return [(f"{obj.__module__}.{obj.__qualname__}", obj) for _, _, obj in public_api.public_callables(EXAMPLE_ROOMS)]


def own_docstring(obj: Any) -> str:
    doc = obj.__dict__.get("__doc__") if inspect.isclass(obj) else obj.__doc__
    return doc or ""


def has_example(doc: str) -> bool:
    """An ``Examples:`` line followed, further down, by a doctest prompt."""
    heading = _EXAMPLES_HEADING.search(doc)
    return heading is not None and ">>> " in doc[heading.end():]


class NumberChecker(doctest.OutputChecker):
    """Exact output, except that each float in the expected text matches the printed float that
    rounds to it at the digits written."""

    def check_output(self, want: str, got: str, optionflags: int) -> bool:
        if super().check_output(want, got, optionflags):
            return True
        if _FLOAT.sub("#", want) != _FLOAT.sub("#", got):
            return False
        for expected, printed in zip(_FLOAT.findall(want), _FLOAT.findall(got)):
            mantissa = expected.lower().split("e")[0]
            exponent = int(expected.lower().split("e")[1]) if "e" in expected.lower() else 0
            half_digit = 0.5 * 10.0 ** (exponent - len(mantissa.split(".")[1]))
            if not abs(float(printed) - float(expected)) <= half_digit * (1 + 1e-12):
                return False
        return True


def run_examples(name: str, obj: Any) -> tuple[int, int, str]:
    """(failed, attempted, report) of the doctests in ``obj``'s own docstring."""
    finder = doctest.DocTestFinder(recurse=False)
    runner = doctest.DocTestRunner(checker=NumberChecker(), optionflags=doctest.ELLIPSIS)
    report: list[str] = []
    for test in finder.find(obj, name, globs={}):
        runner.run(test, out=report.append)
    return runner.failures, runner.tries, "".join(report)


def test_every_public_callable_has_an_example() -> None:
    objects = public_objects()
    assert len(objects) > 90
    missing = [name for name, obj in objects if not has_example(own_docstring(obj)) and name not in WITHOUT_EXAMPLE]
    assert not missing, f"no 'Examples:' section with a doctest: {missing}"


def test_the_exceptions_are_current() -> None:
    """Every name excused above is public and still has no example (a stale entry would hide one)."""
    names = dict(public_objects())
    stale = [n for n in WITHOUT_EXAMPLE if n not in names or has_example(own_docstring(names[n]))]
    assert not stale, stale


def test_the_example_rule_catches_a_missing_example() -> None:
    def documented() -> int:
        """One.

        Examples:

            >>> 1 + 0
            1
        """
        return 1

    def prose_only() -> int:
        """One; see Examples: below (there are none)."""
        return 1

    assert has_example(own_docstring(documented)) and not has_example(own_docstring(prose_only))
    assert run_examples("documented", documented)[:2] == (0, 1)


def test_the_number_rule_compares_at_the_written_digits() -> None:
    checker = NumberChecker()
    assert checker.check_output("(1.1295, 'inside')\n", "(1.12947, 'inside')\n", 0)
    assert not checker.check_output("(1.1295, 'inside')\n", "(1.1297, 'inside')\n", 0)
    assert not checker.check_output("(1.1295, 'inside')\n", "(1.1295, 'outside')\n", 0)
    assert checker.check_output("2.5e-03\n", "2.54e-03\n", 0)
    assert not checker.check_output("2.5e-03\n", "2.56e-03\n", 0)


@pytest.mark.parametrize("name,obj", [(n, o) for n, o in public_objects() if has_example(own_docstring(o))],
                         ids=lambda v: v if isinstance(v, str) else "")
def test_examples_print_what_they_show(name: str, obj: Any) -> None:
    failed, attempted, report = run_examples(name, obj)
    assert attempted > 0
    assert failed == 0, report
