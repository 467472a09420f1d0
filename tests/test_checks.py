"""Argument checks shared by the toolkit (piezolib._checks)."""

import control as ct
import numpy as np
import pytest

from piezolib import _checks as C


@pytest.mark.parametrize("x, kwargs, exc, match", [
    ([1.0, np.nan], {}, ValueError, "x contains 1 non-finite"),
    ([1.0, np.inf], {}, ValueError, "non-finite"),
    (["a", "b"], {}, TypeError, "x must be numeric"),
    ([[1, 2], [3]], {}, TypeError, "x must be"),
    (np.ones((2, 2)), {"ndim": 1}, ValueError, "1-dimensional"),
    (np.ones(1), {"min_length": 2}, ValueError, "at least 2 samples"),
    (np.ones((2, 3)), {"shape": (2, 2)}, ValueError, "shape"),
    (np.array([1 + 1j, 2]), {"real": True}, TypeError, "x must be real-valued"),
])
def test_finite_array_rejects(x, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        C.check_finite_array("x", x, **kwargs)


def test_finite_array_keeps_complex_unless_real_is_asked():
    assert np.iscomplexobj(C.check_finite_array("M", np.array([1 + 1j])))
    assert C.check_finite_array("x", [1, 2], real=True).dtype == float


@pytest.mark.parametrize("sys, part", [
    (ct.tf([np.nan], [1, 1]), "num"),
    (ct.tf([1], [1, np.inf]), "den"),
    (ct.ss([[np.nan]], [[1]], [[1]], [[0]]), "A"),
])
def test_finite_lti_names_the_argument_and_nan(sys, part):
    with pytest.raises(ValueError, match=rf"G has a (NaN|inf) coefficient \(in G\.{part}"):
        C.check_finite_lti("G", sys)


def test_continuous_rejects_discrete_models():
    C.check_continuous("G", ct.tf([1], [1, 1]))
    with pytest.raises(ValueError, match=r"G must be continuous-time.*dt=0\.001"):
        C.check_continuous("G", ct.tf([1], [1, -0.5], 1e-3))


@pytest.mark.parametrize("check, value, exc", [
    (C.check_positive, 0.0, ValueError), (C.check_positive, np.nan, ValueError),
    (C.check_positive, 1 + 1j, TypeError), (C.check_positive, True, TypeError),
    (C.check_nonnegative, -1e-30, ValueError), (C.check_integer, 2.0, TypeError),
    (C.check_real, np.inf, ValueError), (C.check_real, "1", TypeError),
    (C.check_real, np.array([1.0, 2.0]), TypeError),
])
def test_scalars(check, value, exc):
    with pytest.raises(exc, match="v "):
        check("v", value)


def test_proper_and_stable():
    s = ct.tf("s")
    with pytest.raises(ValueError, match="H must be proper"):
        C.check_proper("H", (s + 1) ** 2 / (s + 2))
    with pytest.raises(ValueError, match="H must be stable"):
        C.check_stable("H", 1 / (s - 1))
    with pytest.raises(TypeError, match="H must be a control"):
        C.check_lti("H", np.ones(2))


@pytest.mark.parametrize("check, args, exc, match", [
    (C.check_bool, ("flag", "yes"), TypeError, "flag must be True or False"),
    (C.check_mapping, ("opts", [1]), TypeError, "opts must be a dict"),
    (C.check_mapping, ("opts", {}), ValueError, "opts must not be empty"),
    (C.check_positive_values, ("spreads", [0.1, -1.0]), ValueError, "spreads must be positive"),
    (C.check_positive_values, ("spreads", [0.1, 2.0], 1.0), ValueError, "below 1.0"),
    (C.check_positive_values, ("spreads", "x"), TypeError, "sequence of positive numbers"),
    (C.check_integers, ("orders", []), ValueError, "at least one integer"),
    (C.check_integers, ("orders", [4, 0.5]), TypeError, r"orders\[1\] must be an integer"),
    (C.check_band, ("band_Hz", (50.0, 5.0)), ValueError, "0 <= low < high"),
    (C.check_band, ("band_Hz", "x"), TypeError, "band_Hz must be a pair"),
    (C.check_index_pair, ("pair", (3, 0), (3, 3)), ValueError, "must index a 3 x 3"),
    (C.check_index_pair, ("pair", (-1, 0), (3, 3)), ValueError, r"pair\[0\] must be >= 0"),
    (C.check_count, ("rows", 11, 10), ValueError, "rows must be at most 10, got 11"),
])
def test_the_list_and_size_checks_name_the_argument(check, args, exc, match):
    with pytest.raises(exc, match=match):
        check(*args)


def test_check_count_names_the_limit_and_why():
    with pytest.raises(ValueError, match=r"rows must be at most 10 \(too slow\), got 11"):
        C.check_count("rows", 11, maximum=10, why="too slow")
    with pytest.raises(TypeError, match="rows must be an integer"):
        C.check_count("rows", 2.5, maximum=10)
