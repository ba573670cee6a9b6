"""A kernel first asked for by two threads at once (two files loading beside each other in the window,
issue 34) compiles once and serves both; neither gets numba's "compilation disabled"."""

import threading

import numba
import numpy as np

from groundstation.estimation import base


def kernel_adding(k: float):
    return numba.njit(lambda x: x * 2.0 + k)  # k frozen in as a constant


def test_two_threads_asking_for_a_new_kernel_both_get_it(monkeypatch):
    monkeypatch.setattr(base, "drop_stale_cache", lambda dispatcher: None)  # these have no cache files
    # Several fresh dispatchers: each first use is a race, as when two loads start together.
    kernels = [kernel_adding(k) for k in range(4)]
    errors, results = [], []

    def use(kernel, start):
        start.wait()
        try:
            results.append(base._compiled(kernel, numba.float64(numba.float64))(np.float64(1.0)))
        except Exception as error:  # the defect: RuntimeError("compilation disabled")
            errors.append(error)

    for k, kernel in enumerate(kernels):
        start = threading.Barrier(2)
        threads = [threading.Thread(target=use, args=(kernel, start)) for _ in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert not errors, errors
        assert results[-2:] == [2.0 + k, 2.0 + k]
