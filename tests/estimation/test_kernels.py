"""The compiled batch kernels against each estimator's current ``step`` (through ``run``), sample for sample.

Exact equality is required: the kernels repeat the estimators' arithmetic in the same order, and the
transcendental functions they call (atan2, sqrt, sin, cos, pow) are the same C library's that Python
and NumPy call on this platform. One exception, a diagnostic only: ecf's ``gravity_error`` is
``(...) ** 0.5``, which LLVM compiles to the correctly rounded ``sqrt`` while Python calls ``pow``,
which glibc rounds differently in about 1 sample in 1,000; it is compared to 2 ulp (4.5e-16 relative).
It never feeds back into the state, so the quaternions and biases stay bit for bit equal. The inputs exercise every branch of the robust stepping: waiting for
a usable accelerometer, NaN/Inf gyro, dt NaN/0/negative, accelerometer NaN/Inf/free fall/shock, gaps
longer than max_gap_s with and without a usable accelerometer, and ahf's gyro over-range rule.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from groundstation.estimation import create
from groundstation.estimation.kernels import ahf_kernel, run_ahf, run_ecf

from estimation_samples import flight_like_samples, random_samples

RUNS = {"ahf": run_ahf, "hf": run_ahf, "ecf": run_ecf}
OVERRIDES = [
    ("ahf", {}),
    ("ahf", {"gyro_overrange_rad_s": 1.5, "lowpass": 0.7, "error_gain": 4.0}),
    ("hf", {}),
    ("hf", {"beta": 0.0}),
    ("ecf", {}),
    ("ecf", {"kp": 2.0, "ki": 0.0, "max_gap_s": 0.05}),
]


def damaged_samples(n, seed):
    """Flight-like samples with every kind of bad input the guards handle, at random places."""
    gyr, acc, dt = flight_like_samples(n, seed)
    rng = np.random.default_rng(seed + 1)
    acc[:7] = np.nan  # no usable accelerometer at the start: waiting
    acc[7] = (0.0, 0.0, -0.05)  # free fall, still waiting
    for kind in rng.integers(0, 9, n // 20):
        k = int(rng.integers(8, n))
        if kind == 0:
            gyr[k, rng.integers(3)] = np.nan
        elif kind == 1:
            gyr[k, rng.integers(3)] = rng.choice([np.inf, -np.inf])
        elif kind == 2:
            dt[k] = rng.choice([np.nan, 0.0, -0.01, np.inf])
        elif kind == 3:
            acc[k, rng.integers(3)] = rng.choice([np.nan, np.inf])
        elif kind == 4:
            acc[k] *= 0.1  # free fall
        elif kind == 5:
            acc[k] *= 5.0  # shock
        elif kind == 6:
            dt[k] = rng.uniform(1.5, 30.0)  # a gap: re-initialised from the accelerometer
        elif kind == 7:
            dt[k] = rng.uniform(1.5, 30.0)
            acc[k] = np.nan  # a gap without a usable accelerometer: held
        else:
            gyr[k] *= 10.0  # fast rotation (ahf's over-range rule with its threshold set)
    return gyr, acc, dt


def assert_agree(name, overrides, gyr, acc, dt):
    estimator = create(name, overrides)
    q_step, diag_step = estimator.run(gyr, acc, dt)
    q, diag = RUNS[name](estimator.settings, gyr, acc, dt)
    np.testing.assert_array_equal(q, q_step)
    assert diag.keys() == diag_step.keys()
    for field in diag:
        assert diag[field].dtype == diag_step[field].dtype, field
        if (name, field) == ("ecf", "gravity_error"):  # sqrt vs pow, see the module docstring
            np.testing.assert_allclose(diag[field], diag_step[field], rtol=4.5e-16, atol=0, err_msg=field)
        else:
            np.testing.assert_array_equal(diag[field], diag_step[field], err_msg=field)
    return diag


@pytest.mark.parametrize("name, overrides", OVERRIDES)
def test_kernel_equals_step_on_damaged_flight(name, overrides):
    diag = assert_agree(name, overrides, *damaged_samples(20_000, seed=len(name) + len(overrides)))
    seen = np.bitwise_or.reduce(diag["status"])
    assert seen & 0b11111 == 0b11111  # waiting, initialised, held, acc skipped, re-initialised all occurred


@pytest.mark.parametrize("name, overrides", OVERRIDES)
def test_kernel_equals_step_on_random_motion(name, overrides):
    assert_agree(name, overrides, *random_samples(5_000, seed=7))


finite_or_not = st.one_of(st.floats(-40.0, 40.0), st.sampled_from([math.nan, math.inf, -math.inf, 0.0]))


@settings(max_examples=60, derandomize=True, deadline=None)
@given(
    st.sampled_from(OVERRIDES),
    st.integers(1, 40).flatmap(
        lambda n: st.tuples(
            arrays(float, (n, 3), elements=finite_or_not),
            arrays(float, (n, 3), elements=st.one_of(st.floats(-3.5, 3.5), st.just(math.nan))),
            arrays(float, (n,), elements=st.one_of(st.floats(-0.01, 2.0), st.just(math.nan))),
        )
    ),
)
def test_kernel_equals_step_on_arbitrary_inputs(case, inputs):
    assert_agree(*case, *inputs)


def test_uncompiled_kernel_is_the_same_function():
    """Without numba the kernels run as plain Python; that path gives the same numbers too."""
    compiled = getattr(ahf_kernel, "py_func", None)
    if compiled is None:
        pytest.skip("numba not installed: the kernels already run uncompiled")
    gyr, acc, dt = damaged_samples(500, seed=3)
    args = (gyr, acc, dt, 0.04, 9.0, 1.0, True, 2.0, 0.2, 0.9, 1.0, math.inf, False)
    for a, b in zip(ahf_kernel(*args), ahf_kernel.py_func(*args)):
        np.testing.assert_array_equal(a, b)


def test_length_mismatch_is_refused():
    gyr, acc, dt = random_samples(10, seed=1)
    with pytest.raises(ValueError, match="10 rows"):
        run_ecf(create("ecf").settings, gyr, acc[:5], dt)
