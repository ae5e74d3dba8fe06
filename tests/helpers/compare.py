"""Equality of results that went through the same arithmetic, to the rounding it can carry.

Two runs of the same code on the same data are not promised to agree bit for bit, and a sum
over many cancelling terms (a flux through a hole) shows it first. The tolerance is a few units in the last
place of the quantity's scale, |a - b| <= ulps * eps * max|b|, never a relative tolerance per element.
"""
from __future__ import annotations

import numpy as np


def assert_same_arithmetic(actual, reference, ulps: int = 4, err_msg: str = "") -> None:
    """Assert actual == reference element-wise within ulps * eps * max|reference| (NaNs must coincide)."""
    a, b = np.asarray(actual), np.asarray(reference)
    assert a.shape == b.shape, f"{err_msg}: shapes {a.shape} != {b.shape}"
    if not np.issubdtype(b.dtype, np.floating):
        np.testing.assert_array_equal(a, b, err_msg=err_msg)
        return
    finite = np.isfinite(b)
    scale = float(np.max(np.abs(b[finite]))) if finite.any() else 0.0
    atol = ulps * np.finfo(b.dtype).eps * scale
    np.testing.assert_allclose(a, b, rtol=0, atol=atol, equal_nan=True,
                               err_msg=f"{err_msg} (tolerance {ulps} ulps of the scale {scale:.3e})")
