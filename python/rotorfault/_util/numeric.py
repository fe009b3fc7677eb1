"""The package's one Euclidean norm safe at every magnitude (:func:`scaled_norm`).

NumPy 2's ``np.linalg.norm`` sums the squares of the entries: an entry of 1e200 overflows them to
``inf`` and an entry of 1e-200 underflows them to 0, so a thrust axis of (1e-200, 0, 0) read as
zero and a quaternion component of 1e300 gave an infinite norm. :func:`scaled_norm` divides each
vector by the power of two just above its largest entry first and multiplies the norm back: a
power of two scales every rounding of the sum and the square root exactly, so wherever the plain
norm neither overflows nor underflows the two agree to the last bit (``tests/cross/
test_scaled_norm.py``), and where it would, this one is the true norm (to the last few bits).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


def scaled_norm(values: Any, axis: int | tuple[int, ...] | None = None) -> Any:
    """The Euclidean norm of ``values`` (the Frobenius norm over a tuple ``axis``, of every entry
    with ``axis=None``), as ``np.linalg.norm(values, axis=axis)`` gives it but with no overflow
    or underflow of the squares (module docs): a float for ``axis=None``, else an array of the
    norms along ``axis``. Real or complex entries; non-finite entries give ``inf`` or NaN as
    NumPy's norm does."""
    array = np.asarray(values)
    if array.dtype.kind not in "fc":
        array = array.astype(np.float64)
    magnitude = np.abs(array)
    peak = np.max(magnitude, axis=axis, keepdims=True, initial=0.0)
    # 2^-e with peak in [2^(e-1), 2^e): a power of two, so scaling adds no rounding.
    _, exponent = np.frexp(np.where(np.isfinite(peak) & (peak > 0), peak, 1.0))
    scaled = np.linalg.norm(np.ldexp(array, -exponent) if array.dtype.kind == "f" else array * np.ldexp(1.0, -exponent), axis=axis, keepdims=True)
    norm = np.ldexp(scaled, exponent)
    if axis is None:
        return float(norm.reshape(()))
    return np.asarray(np.squeeze(norm, axis=axis), dtype=np.float64)
