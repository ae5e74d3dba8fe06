"""tests/helpers/compare.py: equal to the rounding of the same arithmetic, measured on the scale, not per element."""
import numpy as np
import pytest

from helpers.compare import assert_same_arithmetic

EPS = np.finfo(float).eps


def test_last_bits_of_a_small_element_pass_a_real_difference_fails():
    ref = np.array([1.0e-10, -3.0e-11, 1.3e-26, 0.0, np.nan])
    near = ref.copy()
    near[2] += 2 * EPS * 1.0e-10                 # 2 ulps of the scale, ~1e-6 relative to the element itself
    assert_same_arithmetic(near, ref)
    far = ref.copy()
    far[0] *= 1 + 1e-12                          # ~4500 ulps of the scale
    with pytest.raises(AssertionError, match="ulps of the scale"):
        assert_same_arithmetic(far, ref, err_msg="hole_flux")
    with pytest.raises(AssertionError):
        assert_same_arithmetic(np.where(np.isnan(ref), 0.0, ref), ref)       # a NaN must stay a NaN
    with pytest.raises(AssertionError, match="shapes"):
        assert_same_arithmetic(ref[:3], ref)


def test_integers_and_strings_compare_exactly():
    assert_same_arithmetic(np.arange(4), np.arange(4))
    with pytest.raises(AssertionError):
        assert_same_arithmetic(np.array([0, 1, 2, 4]), np.arange(4))
