"""The ``rotorfault`` command group and what every command shares: the one-line
``Error: field: rule`` for user errors (exit status 1; click's own usage errors exit with 2; a
missing optional package names its extra), number and rotor-list parsing, Ctrl-C (exit status 130
with one line; an interrupted ``--out`` output says that ``--resume`` completes it) and a report
command's handling of SIGTERM. What a command writes, and in which format, is
:mod:`~rotorfault.cli.output`."""

from __future__ import annotations

import contextlib
import functools
import signal
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar

import click
from rich.console import Console

from .._util.optional import MissingDependency
from .._util.output import claim_output_directory
from ..analysis import ACAI_FORMULAS, Airframe

F = TypeVar("F", bound=Callable[..., Any])

#: A rich console on standard output (the table format's on a terminal; commands write through
#: :class:`rotorfault.cli.output.Output`).
console = Console()


def _user_errors(command: F) -> F:
    """Turns the library's ValueError/TypeError/OSError into click's one-line error."""

    @functools.wraps(command)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return command(*args, **kwargs)
        except (ValueError, TypeError, OSError, OverflowError, ImportError) as exc:
            raise click.ClickException(one_line(str(exc))) from None
        except RecursionError:
            raise click.ClickException("input: nested too deeply to read (a TOML file of arrays or tables within tables?)") from None
        except MemoryError:
            raise click.ClickException("out of memory: ask for a smaller problem") from None

    return wrapper  # type: ignore[return-value]


def one_line(text: str) -> str:
    """``text`` as one line of plain text: every line boundary Python knows (``\\n``, ``\\r``, and
    also ``\\x1c``-``\\x1e``, ``\\x85``, ``\\u2028``, which a TOML parser's message may quote from
    the file: the long hostile run found ``\\x1e``) becomes a space, and any other control
    character (a terminal escape, say) is shown escaped."""
    joined = " ".join(text.splitlines())
    return "".join(c if c.isprintable() or c == " " else c.encode("unicode_escape").decode("ascii") for c in joined)


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

_MASS_KEY = "rotorfault.mass_kg"


def _remember_mass(ctx: click.Context, param: click.Parameter, value: float | None) -> None:
    ctx.meta[_MASS_KEY] = value


#: ``--mass``: the vehicle mass of a PX4 ``.params`` airframe (PX4 keeps none), read by
#: :func:`load_airframe`.
mass_option = click.option(
    "--mass", "mass_kg", type=float, default=None, expose_value=False, callback=_remember_mass, is_eager=True,
    help="Vehicle mass in kg of a PX4 .params airframe (PX4 keeps none; needed when MPC_THR_HOVER cannot give it).",
)


def airframe_option(command: F) -> F:
    """``--airframe`` (a preset, a TOML file or a PX4 .params file) and ``--mass``."""
    command = click.option(
        "--airframe", "-a", required=True, help="Preset name (see `rotorfault airframes`), a TOML file or a PX4 .params file."
    )(command)
    return mass_option(command)


def load_airframe(spec: str) -> Airframe:
    """The airframe ``--airframe`` names, with ``--mass`` for a PX4 file."""
    ctx = click.get_current_context(silent=True)
    mass = None if ctx is None else ctx.meta.get(_MASS_KEY)
    return Airframe.load(spec, mass_kg=mass)


def claim_output(field: str, path: str, *, force: bool) -> Path:
    """Holds the output directory ``path`` until the command ends, checked before any work:
    its lock (a second writer is refused, naming this one), an interrupted run's leftovers
    recovered, then the directory checked (:func:`rotorfault._util.output.claim_output_directory`)."""
    return click.get_current_context().with_resource(claim_output_directory(field, path, force=force))


#: The exit status of a command stopped by Ctrl-C (128 + SIGINT, as shells report it).
EXIT_INTERRUPTED = 130


class Interrupted(click.ClickException):
    """Ctrl-C: one line on standard error and exit status 130 (click's own handling prints
    ``Aborted!`` and exits 1, which a script cannot tell from a failure)."""

    exit_code = EXIT_INTERRUPTED


@contextlib.contextmanager
def resumable_interruptions(out_path: str | None) -> Iterator[None]:
    """A study's work: Ctrl-C ends the command with :class:`Interrupted`, saying whether the
    ``--out`` output can be completed (its chunks are written whole, so ``--resume`` can)."""
    try:
        yield
    except KeyboardInterrupt:
        if out_path is None:
            raise Interrupted("interrupted (Ctrl-C): nothing written") from None
        raise Interrupted(
            f"interrupted (Ctrl-C): {out_path} keeps the chunks written; the same command with --resume completes it"
        ) from None


class _Group(click.Group):
    """The command group: Ctrl-C anywhere in a command is :class:`Interrupted` (exit status 130)."""

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt:
            raise Interrupted("interrupted (Ctrl-C)") from None


@click.group(cls=_Group)
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
    is cleaned up) and SIGTERM (exit status 1) or Ctrl-C (:class:`Interrupted`, 130) end with a
    one-line message saying the previous report is unchanged. Outside the main thread (an embedding application) SIGTERM is left alone."""
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
        raise Interrupted("interrupted (Ctrl-C): no report written, the previous one is unchanged") from None
    finally:
        if in_main:
            signal.signal(signal.SIGTERM, previous)


def main() -> None:
    cli()
