"""Test-wide setup: Qt never needs a display (CI has none)."""

import os

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
