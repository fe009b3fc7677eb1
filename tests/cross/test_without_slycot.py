"""The slycot-hiding harness itself (tests/without_slycot.py)."""

from __future__ import annotations

from without_slycot import run_without_slycot


def test_slycot_is_hidden_in_the_subprocess() -> None:
    """In the subprocess ``import slycot`` fails and python-control knows it."""
    result = run_without_slycot(
        """
        import json
        try:
            import slycot  # noqa: F401
            found = True
        except ImportError:
            found = False
        print(json.dumps({"found": found}))
        """
    )
    assert result == {"found": False}
