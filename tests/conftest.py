"""Test-wide setup: Qt never needs a display (CI has none); hypothesis reproducible and without deadlines;
garbage collected between tests in the main thread.

hypothesis: no deadline anywhere (a loaded 2-core machine takes several times a test's usual time, and a
deadline then fails a correct test); with the environment variable ``CI`` set, examples are derived
from each test's name (``derandomize``), so every CI run tries the same examples; elsewhere they are
random, and a failure prints the ``@reproduce_failure`` blob and the falsifying example, to be pinned as an
``@example`` in the test.
"""

import gc
import os

import pytest
from hypothesis import settings

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

settings.register_profile("groundstation", deadline=None, print_blob=True)
settings.register_profile("ci", settings.get_profile("groundstation"), derandomize=True)
settings.load_profile("ci" if os.environ.get("CI") else "groundstation")


@pytest.fixture(autouse=True)
def collect_in_the_main_thread():
    """The window turns Python's automatic collection off (ui/gui_collector.py: a collection in a loading
    thread can deadlock with Qt); between tests the garbage is collected here, in the main thread, and
    what survives is frozen so that the next collection costs one test's garbage, not the whole heap."""
    yield
    gc.collect()
    gc.freeze()


@pytest.fixture(scope="session", autouse=True)
def compiled_estimators():
    """The live estimators' kernels and batch loops compiled (or loaded from the cache: about a second) before
    any test. A live session does not wait for them: until they are compiled it runs them interpreted (within
    1e-12) and leaves ukf and sssrukf out (``session_parts.estimators.EstimatorBank``), and a file opened in the
    app is computed without them (``session_makers.load.Loading``); the tests that compare a live session with
    a batch run bit for bit, or read a file's estimators in the window, see what every start but a machine's
    first gives. The first start itself is tested in processes with an empty cache of their own
    (tests/session/test_first_start.py, tests/ui/test_first_start.py)."""
    import numpy as np

    from groundstation.estimation import create, live_estimators

    one = np.zeros((1, 3))
    for name in live_estimators():
        create(name).run(one, one, np.ones(1))
