"""Builds the desktop bundle: ``python bundle/build.py [--dist DIR] [--work DIR]``.

One folder (``DIR/groundstation/``) with the ``groundstation`` executable (``groundstation.exe`` on
Windows) and everything it needs: no Python installation on the user's machine. Build it on the system
it is for (PyInstaller does not cross-compile): docs/bundle.md. Needs ``pip install pyinstaller``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def build(dist: Path, work: Path) -> Path | None:
    """Runs PyInstaller on the spec; returns the executable's path (None when PyInstaller failed: it said why)."""
    # Offscreen: PyInstaller imports Qt to find its plugins, which must not need a display.
    environment = {**os.environ, "QT_QPA_PLATFORM": "offscreen"}
    done = subprocess.run([sys.executable, "-m", "PyInstaller", "--noconfirm", "--clean", "--log-level", "WARN",
                           "--distpath", str(dist), "--workpath", str(work), str(HERE / "groundstation.spec")],
                          env=environment)
    if done.returncode:
        return None
    return dist / "groundstation" / ("groundstation.exe" if sys.platform == "win32" else "groundstation")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dist", type=Path, default=HERE.parent / "dist", help="where the bundle goes (default: dist/)")
    parser.add_argument("--work", type=Path, default=HERE.parent / "build", help="PyInstaller's work folder (default: build/)")
    args = parser.parse_args()
    try:
        import PyInstaller  # noqa: F401
    except ImportError:
        print("bundle/build.py needs PyInstaller: pip install pyinstaller", file=sys.stderr)
        return 2
    executable = build(args.dist, args.work)
    if executable is None:
        print("bundle/build.py: PyInstaller failed (its messages are above)", file=sys.stderr)
        return 1
    print(f"built {executable}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
