"""Custom-series expressions: a whitelist over ``ast``, never ``eval`` of the text."""

import threading
import time

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


@pytest.mark.parametrize("text, value", [
    ("ahf2_roll_deg + 10**10**10", "inf"),  # a Python integer power: the interpreter held for ever
    ("ahf2_roll_deg + 1/0", "inf"),
    ("ahf2_roll_deg + 10**400", "inf"),
    ("ahf2_roll_deg * 0**-1", "inf"),
    ("ahf2_roll_deg + 1" + "0" * 400, "inf"),  # an integer literal beyond float64
    ("ahf2_roll_deg % (2 % 0)", "nan"),
    ("log(0) + ahf2_roll_deg", "-inf"),
    ("sqrt(-1) * ahf2_roll_deg", "nan"),
])
def test_a_part_of_numbers_only_that_is_no_finite_float_is_refused_at_once(text, value):
    with pytest.raises(ExpressionError, match=f" is {value} in float64"):  # float64 from the parse: no integer power
        Expression(text, KNOWN)


def test_numbers_are_float64_and_on_channels_overflow_gives_inf_not_an_exception():
    e = Expression("ahf2_roll_deg ** 400 + onboard_roll_deg ** -1 + 3 % onboard_roll_deg", KNOWN)
    # Integer columns too: numpy's integer ``**`` refuses negative powers and wraps on overflow.
    got = e.evaluate({"ahf2_roll_deg": np.array([10, 2, 0]), "onboard_roll_deg": np.array([0, 2, 4])})
    assert got.dtype == np.float64
    assert np.isnan(got[0])  # inf + inf + (3 % 0: NaN)
    assert got[1] == 2.0**400 + 0.5 + 1.0 and got[2] == 0.0 + 0.25 + 3.0  # Python's floats


@pytest.mark.parametrize("text, says", [
    ("log(ahf2_roll_deg, onboard_roll_deg)", r"log\(\) takes 1 value, not 2"),  # numpy's second value: out=
    ("abs(ahf2_roll_deg, ahf2_roll_deg)", r"abs\(\) takes 1 value, not 2"),
    ("arctan2(ahf2_roll_deg)", r"arctan2\(\) takes 2 values, not 1"),
    ("minimum(ahf2_roll_deg, 1, onboard_roll_deg)", r"minimum\(\) takes 2 values, not 3"),
    ("sqrt()", r"sqrt\(\) takes 1 value, not 0"),
    ("sqrt(*ahf2_roll_deg)", "without names"),
    ("sqrt(ahf2_roll_deg, out=onboard_roll_deg)", "without names"),
])
def test_each_function_takes_its_own_number_of_values(text, says):
    with pytest.raises(ExpressionError, match=says):
        Expression(text, KNOWN)


def test_a_second_value_never_reaches_numpy_as_its_output():
    a, b = np.array([2.0, 3.0]), np.array([5.0, 7.0])
    with pytest.raises(ExpressionError):
        Expression("log(abs(ahf2_roll_deg), onboard_roll_deg) + onboard_roll_deg", KNOWN).evaluate(
            {"ahf2_roll_deg": a, "onboard_roll_deg": b})
    assert np.array_equal(b, [5.0, 7.0])


@pytest.mark.parametrize("text, says", [
    ("-" * 5000 + "ahf2_roll_deg", "characters long"),
    ("+".join(["ahf2_roll_deg"] * 75), "characters long"),
    ("+".join(["1"] * 300), "parts"),
    ("-" * 600 + "ahf2_roll_deg", "parts"),
    ("(" * 300 + "ahf2_roll_deg" + ")" * 300, "not an expression"),
    ("ahf2_roll_deg\0", "not an expression"),
])
def test_a_long_or_deep_expression_is_refused_with_a_message(text, says):
    with pytest.raises(ExpressionError, match=says):
        Expression(text, KNOWN)


def test_evaluating_stops_past_its_time_budget():
    e = Expression("+".join(["sin(ahf2_roll_deg)"] * 40), KNOWN)
    rows = np.random.default_rng(7).normal(size=200_000)
    assert np.allclose(e.evaluate({"ahf2_roll_deg": rows}, budget_s=60.0), 40 * np.sin(rows))
    with pytest.raises(ExpressionError, match="took longer than 1e-09 s"):
        e.evaluate({"ahf2_roll_deg": rows}, budget_s=1e-9)


HOSTILE = ["ahf2_roll_deg + 10**10**10", "ahf2_roll_deg + 9**9**9", "ahf2_roll_deg ** 10**10**10",
           "exp(exp(exp(ahf2_roll_deg * 1000))) % 0", "ahf2_roll_deg + 1/0", "ahf2_roll_deg + 10**400",
           "0**-1 * ahf2_roll_deg", "log(ahf2_roll_deg, onboard_roll_deg)", "-" * 199 + "ahf2_roll_deg"]


def test_no_typed_expression_stops_another_thread():
    """A thread counting while every hostile expression is parsed and evaluated on a second thread:
    the evaluations end and the count goes on (generous limits: nothing here waits on a short time)."""
    counted, stop, finished = [0], threading.Event(), []
    values = {"ahf2_roll_deg": np.linspace(-180, 180, 10_000), "onboard_roll_deg": np.ones(10_000)}

    def count():
        while not stop.is_set():
            counted[0] += 1
            time.sleep(0.001)

    def evaluate_all():
        for text in HOSTILE:
            try:
                Expression(text, KNOWN).evaluate(values)
            except ExpressionError:
                pass
            finished.append(text)

    counter = threading.Thread(target=count, daemon=True)
    counter.start()
    worker = threading.Thread(target=evaluate_all, daemon=True)
    worker.start()
    worker.join(timeout=120)
    at_the_end = counted[0]
    assert finished == HOSTILE, f"still evaluating {HOSTILE[len(finished)]!r} after 120 s"
    deadline = time.monotonic() + 60
    while counted[0] == at_the_end and time.monotonic() < deadline:
        time.sleep(0.01)
    stop.set()
    assert counted[0] > at_the_end


def test_another_sessions_channel_is_named_as_the_channels_tab_lists_it():
    known = KNOWN | {"S2:imu.gyr_x_rad_s", "S2:ahf2_roll_deg"}
    a, b, c = np.array([1.0, 2.0]), np.array([3.0, 5.0]), np.array([7.0, 11.0])
    e = Expression("S2:imu.gyr_x_rad_s - imu.gyr_x_rad_s + S2:ahf2_roll_deg*2", known)
    assert e.names == ["S2:imu.gyr_x_rad_s", "imu.gyr_x_rad_s", "S2:ahf2_roll_deg"]
    got = e.evaluate({"S2:imu.gyr_x_rad_s": a, "imu.gyr_x_rad_s": b, "S2:ahf2_roll_deg": c})
    assert np.array_equal(got, a - b + c * 2)
    with pytest.raises(ExpressionError, match="unknown channel 'S2.imu.gyr_x_rad_s'"):  # the colon is the session's mark
        Expression("S2.imu.gyr_x_rad_s", known)
    with pytest.raises(ExpressionError, match="unknown channel 'S3:imu.gyr_x_rad_s': there is no session S3 in this window"):
        Expression("S3:imu.gyr_x_rad_s + 1", known)
    with pytest.raises(ExpressionError, match="unknown channel 'S2:imu.nosuch'$"):  # S2 is there, not its channel
        Expression("S2:imu.nosuch", known)
    with pytest.raises(ExpressionError, match="not an expression"):  # a colon with space around is no session's
        Expression("S2 : imu.gyr_x_rad_s", known)
