"""The ``rotorfault`` command group and what every command shares: the console, the one-line
``Error: field: rule`` for user errors (exit status 1; click's own usage errors exit with 2),
number and rotor-list parsing, and a report command's handling of SIGTERM and Ctrl-C."""

from __future__ import annotations

import contextlib
import functools
import signal
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

import click
from rich.console import Console

from ..analysis import ACAI_FORMULAS

F = TypeVar("F", bound=Callable[..., Any])

console = Console()


def _user_errors(command: F) -> F:
    """Turns the library's ValueError/TypeError/OSError into click's one-line error."""

    @functools.wraps(command)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return command(*args, **kwargs)
        except (ValueError, TypeError, OSError, OverflowError) as exc:
            raise click.ClickException(str(exc).replace("\n", " ")) from None
        except RecursionError:
            raise click.ClickException("input: nested too deeply to read (a TOML file of arrays or tables within tables?)") from None
        except MemoryError:
            raise click.ClickException("out of memory: ask for a smaller problem") from None

    return wrapper  # type: ignore[return-value]


def parse_numbers(field: str, text: str) -> list[float]:
    try:
        return [float(part) for part in text.split(",")]
    except ValueError:
        raise ValueError(f"{field}: expected comma-separated numbers, got {text!r}") from None


def parse_rotors(field: str, text: str) -> list[int]:
    try:
        return [int(part) for part in text.split(",")]
    except ValueError:
        raise ValueError(f"{field}: expected comma-separated rotor numbers, got {text!r}") from None


formula_option = click.option(
    "--formula",
    type=click.Choice(list(ACAI_FORMULAS)),
    default="eq13",
    show_default=True,
    help="Which ACAI: eq13 (Du's eq. (13), as the paper prints it; 0 where hover is infeasible) or facet-margin "
    "(negative where hover is infeasible). Every printed ACAI names its formula.",
)

airframe_option = click.option(
    "--airframe", "-a", required=True, help="Preset name (see `rotorfault airframes`) or a TOML file."
)


@click.group()
@click.version_option(package_name="rotorfault")
def cli() -> None:
    """rotorfault: will this multirotor stay controllable when rotors degrade or fail?"""


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread so that partial outputs are cleaned up (a
    BaseException, like KeyboardInterrupt, so no library's `except Exception` swallows it)."""


def _raise_terminated(signum: int, frame: Any) -> None:
    raise _Terminated()


@contextlib.contextmanager
def _report_interruptions() -> Iterator[None]:
    """A report command's work: SIGTERM becomes an exception (so the temporary report directory
    is cleaned up) and SIGTERM or Ctrl-C end with a one-line message saying the previous report is
    unchanged. Outside the main thread (an embedding application) SIGTERM is left alone."""
    previous = signal.getsignal(signal.SIGTERM)
    in_main = True
    try:
        signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:
        in_main = False
    try:
        yield
    except _Terminated:
        raise click.ClickException("terminated (SIGTERM): no report written, the previous one is unchanged") from None
    except KeyboardInterrupt:
        raise click.ClickException("interrupted: no report written, the previous one is unchanged") from None
    finally:
        if in_main:
            signal.signal(signal.SIGTERM, previous)


def main() -> None:
    cli()
