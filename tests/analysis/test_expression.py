"""Custom-series expressions: a whitelist over ``ast``, never ``eval`` of the text."""

import numpy as np
import pytest

from groundstation.analysis.expression import Expression, ExpressionError, at_or_before

KNOWN = {"ahf2_roll_deg", "onboard_roll_deg", "imu.gyr_x_rad_s", "position.pos_n_m", "position.pos_e_m"}


def test_arithmetic_and_numpy_functions_of_channels():
    a, b = np.array([1.0, -2.0, 3.0]), np.array([0.5, 0.5, -4.0])
    e = Expression("abs(ahf2_roll_deg - onboard_roll_deg) * 2 + degrees(arctan2(position.pos_e_m, position.pos_n_m)) ** 1",
                   KNOWN)
    assert e.names == ["ahf2_roll_deg", "onboard_roll_deg", "position.pos_e_m", "position.pos_n_m"]
    got = e.evaluate({"ahf2_roll_deg": a, "onboard_roll_deg": b, "position.pos_e_m": b, "position.pos_n_m": a})
    assert np.array_equal(got, np.abs(a - b) * 2 + np.degrees(np.arctan2(b, a)))
    assert np.allclose(Expression("sqrt(-imu.gyr_x_rad_s) + pi", KNOWN).evaluate({"imu.gyr_x_rad_s": -a}), np.sqrt(a) + np.pi, equal_nan=True)


@pytest.mark.parametrize("text, says", [
    ("", "empty"),
    ("ahf2_roll_deg +* 2", "not an expression"),
    ("__import__('os').system('true')", "unknown function"),
    ("ahf2_roll_deg.__class__", "unknown channel"),
    ("open('x')", "unknown function"),
    ("nosuch_deg * 2", "unknown channel 'nosuch_deg'"),
    ("[ahf2_roll_deg]", "not allowed"),
    ("ahf2_roll_deg if 1 else 2", "not allowed"),
    ("lambda: 1", "not allowed"),
    ("'text'", "not allowed"),
    ("sqrt", "functions are called"),
    ("sqrt(x=ahf2_roll_deg)", "without names"),
])
def test_anything_else_is_refused_with_a_message(text, says):
    with pytest.raises(ExpressionError, match=says):
        Expression(text, KNOWN)


def test_a_function_given_the_wrong_number_of_values_says_so():
    with pytest.raises(ExpressionError, match="arctan2"):
        Expression("arctan2(ahf2_roll_deg)", KNOWN).evaluate({"ahf2_roll_deg": np.ones(2)})


def test_another_tables_column_is_its_newest_row_at_or_before_each_time():
    got = at_or_before(np.array([0.5, 1.0, 1.5, 3.0]), np.array([1.0, 2.0]), np.array([10.0, 20.0]))
    assert np.array_equal(got, [np.nan, 10.0, 10.0, 20.0], equal_nan=True)
