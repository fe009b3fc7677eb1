"""The ``rotorfault`` command line, one module per room it serves: :mod:`~rotorfault.cli.analysis`
(``airframes``, ``acai``, ``failures``, ``certify``), :mod:`~rotorfault.cli.studies` (``scan``,
``design``, ``simulate``, ``campaign``), :mod:`~rotorfault.cli.papers` (``ftc-report``,
``vpp-report``, ``lanzon-report``, ``reproduce``), on the group and helpers of
:mod:`~rotorfault.cli.app`.

The CLI only calls the public API: it may import the rooms' public modules and names,
``rotorfault._typing`` and ``rotorfault._util`` (outputs checked before work), never a private
module of a room or the extension module; nothing in the package imports the CLI
(``tests/cross/test_architecture.py``).
"""

from . import analysis, papers, studies  # noqa: F401  (registers the commands on the group)
from .app import cli, console, main
from .papers import _print_ftc_table

__all__ = ["cli", "console", "main"]
