"""numba's cache folder is the user's, set as numba is first imported, not when the estimators' registry
is (the commands' help imports the registry and never numba)."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

PROBE = """
import os, sys
import groundstation.estimation
from groundstation.estimation.compiled_cache import sources_hash, user_cache_root
assert "NUMBA_CACHE_DIR" not in os.environ and "numba" not in sys.modules
import numba
assert numba.config.CACHE_DIR == os.environ["NUMBA_CACHE_DIR"] == str(user_cache_root() / "numba" / sources_hash())
"""


def test_the_cache_folder_is_set_as_numba_is_first_imported():
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    done = subprocess.run([sys.executable, "-c", PROBE], env={**env, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr


def test_a_folder_the_user_names_wins():
    probe = "import os, groundstation.estimation, numba; assert numba.config.CACHE_DIR == os.environ['NUMBA_CACHE_DIR'] == '/tmp/mine'"
    done = subprocess.run([sys.executable, "-c", probe], env={**os.environ, "PYTHONPATH": str(ROOT), "NUMBA_CACHE_DIR": "/tmp/mine"},
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
