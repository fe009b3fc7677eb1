"""Private helpers every room may use, and nothing else: converting user input to the arrays the
core reads (:mod:`~rotorfault._util.convert`), files written atomically and checked before any
work (:mod:`~rotorfault._util.output`), the progress bar of long calls
(:mod:`~rotorfault._util.progress`) and the one way an old name keeps working for a release
(:mod:`~rotorfault._util.deprecation`). These modules import only the extension module and each
other, never a room: they are the floor of the house (``tests/cross/test_architecture.py``).
"""
