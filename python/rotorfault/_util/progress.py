"""One progress bar for long calls: chunks of work with count, rate and ETA (rich), on request."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING

from .convert import flag

if TYPE_CHECKING:
    from rich.progress import ProgressColumn, Task
    from rich.text import Text


def chunks(total: int, size: int, *, description: str, show: bool | None, default_show: bool = False) -> Iterator[tuple[int, int]]:
    """``(start, stop)`` ranges covering ``0..total`` in pieces of ``size``; with ``show`` (or, when
    it is ``None``, ``default_show``) a rich progress bar counts the items done, with rate and ETA.
    The bar goes to standard error, so it never mixes with a command's output."""
    visible = default_show if show is None else flag("progress", show)
    ranges = [(start, min(start + size, total)) for start in range(0, total, max(size, 1))]
    if not visible:
        yield from ranges
        return
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), _rate_column(), TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(*columns, console=Console(stderr=True)) as bar:
        task = bar.add_task(description, total=total)
        for start, stop in ranges:
            yield start, stop
            bar.advance(task, stop - start)


@contextlib.contextmanager
def progress_bar(total: int, *, description: str, show: bool | None, default_show: bool = False, completed: int = 0) -> Iterator[Callable[[int], None]]:
    """A bar counting ``total`` items (``completed`` already done, e.g. on resume) with rate and
    ETA on standard error; yields ``advance(items)``. Hidden unless ``show`` (or, when it is
    ``None``, ``default_show``); the rate counts only the items done in this run."""
    visible = default_show if show is None else flag("progress", show)
    if not visible:
        yield lambda items: None
        return
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), _rate_column(), TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(*columns, console=Console(stderr=True)) as bar:
        task = bar.add_task(description, total=total, completed=completed)
        # rich's speed comes from the samples since the start: begin them after the skipped part.
        bar.reset(task, total=total, completed=completed)

        def advance(items: int) -> None:
            bar.advance(task, items)

        yield advance


def _rate_column() -> ProgressColumn:
    from rich.progress import ProgressColumn
    from rich.text import Text

    class RateColumn(ProgressColumn):
        """Items per second (rich's own speed column counts bytes)."""

        def render(self, task: Task) -> Text:
            speed = task.finished_speed or task.speed
            return Text("-/s" if speed is None else f"{speed:,.0f}/s", style="progress.data.speed")

    return RateColumn()
