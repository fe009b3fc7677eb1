"""Run the command line in a real process that signals itself right after its n-th chunk file is
written: an interruption at a known point of the job, whatever the machine's speed.

Polling the output directory from outside and signalling when a chunk appears lost the race on a
fast machine: a small campaign (24 runs of 3 s, 23 ms of work) finished between two looks. Here
the writer's own ``write_chunk`` sends the signal after the chunk is in place, so the process is
stopped with the rest of the job still to do. The signal is the operating system's: SIGKILL ends
the process with its lock; SIGINT reaches the command line's Ctrl-C handling as a keypress would
(a signal arriving during a long Rust call is ``tests/cross/test_interrupt.py``'s case).

Usage: ``proc = run_signalled(args, after_chunks=2, signum=signal.SIGKILL)``.
"""

from __future__ import annotations

import signal
import subprocess
import sys

_SCRIPT = """
import os, signal, sys
# Python's own Ctrl-C handler even when the test runner was started with SIGINT ignored (a
# background job of a non-interactive shell): the child inherits the ignore, installs none, and
# would finish the job instead of stopping.
signal.signal(signal.SIGINT, signal.default_int_handler)
from rotorfault.studies import engine
from rotorfault.cli import cli

after_chunks, signum = int(sys.argv[1]), int(sys.argv[2])
original = engine.write_chunk
written = 0

def write_chunk(*args, **kwargs):
    global written
    original(*args, **kwargs)
    written += 1
    if written == after_chunks:
        os.kill(os.getpid(), signum)

engine.write_chunk = write_chunk
cli.main(args=sys.argv[3:], prog_name="rotorfault")
"""


def run_signalled(args: list[str], *, after_chunks: int, signum: signal.Signals) -> subprocess.CompletedProcess[str]:
    """Runs ``rotorfault <args>``; the process signals itself right after its ``after_chunks``-th chunk."""
    return subprocess.run([sys.executable, "-c", _SCRIPT, str(after_chunks), str(int(signum)), *args],
                          capture_output=True, text=True, timeout=600, check=False)
