"""``_checks``: check_array (dimensions, dtype, finiteness), check_positive, check_poisson."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import KNOWN_SENSORS, InputError, ShapeError, default_calibration_path
from tactilevision._assets import asset_dir
from tactilevision._checks import check_array


def test_error_hierarchy():
    # ShapeError is an InputError (CLI exit 2) and a ValueError (numpy idiom)
    assert issubclass(ShapeError, InputError)
    assert issubclass(ShapeError, ValueError)


def test_returns_same_array_without_copy():
    x = np.zeros((4, 5, 3), np.uint8)
    assert check_array(x, "x", [("H", "W", 3)]) is x


def test_converts_lists_without_recasting():
    out = check_array([[1, 2], [3, 4]], "x", [(2, 2)])
    assert isinstance(out, np.ndarray)
    assert out.shape == (2, 2)
    assert np.issubdtype(out.dtype, np.integer)


@pytest.mark.parametrize("shape", [(4, 5), (1, 1), (7, 3)])
def test_named_dims_accept_any_size(shape):
    assert check_array(np.zeros(shape), "a", [("H", "W")]).shape == shape


def test_named_dims_must_agree():
    check_array(np.zeros((3, 3)), "a", [("N", "N")])
    with pytest.raises(ShapeError) as exc:
        check_array(np.zeros((3, 4)), "square", [("N", "N")])
    msg = str(exc.value)
    assert "square" in msg
    assert "(N, N)" in msg
    assert "(3, 4)" in msg


def test_fixed_dim_and_wildcard():
    check_array(np.zeros((10, 8)), "inputs", [(None, 8)])
    with pytest.raises(ShapeError, match=r"inputs must have shape \(\?, 8\), got \(10, 7\)"):
        check_array(np.zeros((10, 7)), "inputs", [(None, 8)])


def test_alternative_shapes_listed_with_or():
    shapes = [("H", "W", 3), ("N", "H", "W", 3)]
    check_array(np.zeros((2, 4, 5, 3)), "frames", shapes)
    with pytest.raises(ShapeError) as exc:
        check_array(np.zeros((4, 5)), "frames", shapes)
    msg = str(exc.value)
    assert "frames" in msg
    assert "(H, W, 3) or (N, H, W, 3)" in msg
    assert "got (4, 5)" in msg


def test_wrong_ndim_rejected():
    with pytest.raises(ShapeError, match="vec"):
        check_array(np.zeros((3, 1)), "vec", [("M",)])


@pytest.mark.parametrize(("dtype", "value", "want"), [
    (np.floating, np.zeros(3, np.int64), "must have dtype float, got int64"),
    (np.uint8, np.zeros(3, np.float32), "must have dtype uint8, got float32"),
    (np.integer, np.zeros(3, np.float64), "must have dtype integer, got float64"),
    ((np.floating, np.integer), np.zeros(3, bool), "must have dtype float or integer, got bool"),
])
def test_dtype_messages(dtype, value, want):
    with pytest.raises(ShapeError) as exc:
        check_array(value, "arg", [(3,)], dtype=dtype)
    assert str(exc.value) == f"arg {want}"


def test_dtype_accepts_subtypes():
    check_array(np.zeros(3, np.float32), "a", [(3,)], dtype=np.floating)
    check_array(np.zeros(3, np.float64), "a", [(3,)], dtype=np.floating)
    check_array(np.zeros(3, np.uint16), "a", [(3,)], dtype=np.integer)


def test_shape_checked_before_dtype():
    with pytest.raises(ShapeError, match="shape"):
        check_array(np.zeros((2, 2), np.int64), "a", [(3,)], dtype=np.floating)


def test_finite_counts_bad_values():
    x = np.array([1.0, np.nan, np.inf, -np.inf, 2.0])
    check_array(x, "x", [(5,)])  # finiteness only checked on request
    with pytest.raises(ShapeError, match=r"x must be finite, found 3 NaN or infinite value"):
        check_array(x, "x", [(5,)], finite=True)


def test_unknown_sensor_has_no_default_calibration():
    with pytest.raises(InputError, match="no-such-sensor"):
        default_calibration_path("no-such-sensor")
    assert "gelsight" in KNOWN_SENSORS


def test_asset_dir_kind_checked():
    with pytest.raises(ValueError, match="kind"):
        asset_dir("weights")
    assert asset_dir("calibration").is_dir()


def test_check_positive_and_check_poisson():
    from tactilevision._checks import check_poisson, check_positive

    assert check_positive(np.float32(2.5), "h") == 2.5
    assert check_positive(3, "h") == 3.0
    for bad in (0, -1.0, float("nan"), float("inf"), True, "3", 1j, np.ones(2), None):
        with pytest.raises(InputError, match="thickness_mm"):
            check_positive(bad, "thickness_mm")
    assert check_poisson(0.0) == 0.0 and check_poisson(np.float64(0.49)) == 0.49
    for bad in (0.5, -0.1, float("nan"), "0.3", False):
        with pytest.raises(InputError, match=r"nu must be"):
            check_poisson(bad)
