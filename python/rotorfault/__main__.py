"""``python -m rotorfault``: the same command line as the ``rotorfault`` script."""

from .cli import main

main()
