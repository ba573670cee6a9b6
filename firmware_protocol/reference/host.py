"""The firmware core on the host: compiled with the system C compiler into a cache, loaded with ctypes.

    core = FlightCore(rate_hz=100, accel_fs_g=4, gyro_fs_dps=500, mounting=1, mode=GS_MODE_BOTH, ...)
    frames = core.sample(t_us, registers, battery_v, cpu_load_pct)   # bytes: whole frames, back to back

The library is built once per source version into ``$XDG_CACHE_HOME/groundstation`` (default
``~/.cache/groundstation``), never into the source tree, with the flags the tests hold the core to
(``-std=c99 -Wall -Wextra -Werror``, no floating-point contraction). ``CoreUnavailable`` says why
it cannot be built (no compiler, or the compiler's errors).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

REFERENCE_DIR = Path(__file__).parent
CORE_DIR = REFERENCE_DIR / "core"
PROTOCOL_HEADER_DIR = REFERENCE_DIR.parent / "c"
SOURCES = (*sorted(CORE_DIR.glob("*.c")), REFERENCE_DIR / "host" / "gs_host.c")
HEADERS = (*sorted(CORE_DIR.glob("*.h")), PROTOCOL_HEADER_DIR / "gs_protocol.h")
# Warnings are errors: the core must stay clean C99. No FMA contraction: it changes the last bits.
CFLAGS = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wconversion", "-Wshadow", "-Werror", "-O2", "-ffp-contract=off")


class CoreUnavailable(RuntimeError):
    """The C core cannot be built here (the message says why)."""


def compiler() -> str | None:
    """The system C compiler (``cc``, ``gcc`` or ``clang``), or None."""
    return shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")


def cache_dir() -> Path:
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "groundstation"


def compile_command(cc: str, output: Path, extra: tuple[str, ...] = ()) -> list[str]:
    includes = ["-I", str(CORE_DIR), "-I", str(PROTOCOL_HEADER_DIR)]
    return [cc, *CFLAGS, *extra, *includes, *map(str, SOURCES), "-o", str(output), "-lm"]


def build_library(directory: Path | None = None) -> Path:
    """The shared library of the core (built if this source version has not been yet)."""
    cc = compiler()
    if cc is None:
        raise CoreUnavailable("no C compiler (cc, gcc or clang) on this machine: the C firmware core cannot be built")
    digest = hashlib.sha256(" ".join([cc, *CFLAGS]).encode())
    for path in (*SOURCES, *HEADERS):
        digest.update(path.read_bytes())
    directory = cache_dir() if directory is None else directory
    library = directory / f"libgs_core-{digest.hexdigest()[:16]}.so"
    if library.exists():
        return library
    directory.mkdir(parents=True, exist_ok=True)
    # Built beside its final name and renamed: parallel builds never load half a file.
    with tempfile.TemporaryDirectory(dir=directory) as work:
        temporary = Path(work) / library.name
        result = subprocess.run(compile_command(cc, temporary, ("-fPIC", "-shared")), capture_output=True, text=True)
        if result.returncode != 0:
            raise CoreUnavailable(f"the C firmware core does not compile with {cc}:\n{result.stderr}")
        os.replace(temporary, library)
    return library


_LIBRARY: ctypes.CDLL | None = None


def library() -> ctypes.CDLL:
    global _LIBRARY
    if _LIBRARY is None:
        lib = ctypes.CDLL(str(build_library()))
        P, F, D, U, I = ctypes.c_void_p, ctypes.POINTER(ctypes.c_float), ctypes.POINTER(ctypes.c_double), ctypes.c_uint, ctypes.c_int
        B, S = ctypes.c_char_p, ctypes.c_size_t
        signatures = {
            "gs_host_sizeof_ahf": (S, []), "gs_host_sizeof_flight": (S, []), "gs_host_sizeof_deframer": (S, []),
            "gs_host_max_out": (S, []),
            "gs_host_ahf_init": (I, [P, D, F]),
            "gs_host_ahf_step": (U, [P, F, F, ctypes.c_float, F]),
            "gs_host_flight_init": (I, [P, ctypes.POINTER(U), ctypes.c_double, D]),
            "gs_host_flight_sample": (S, [P, ctypes.c_uint32, ctypes.POINTER(ctypes.c_int16), D, B, S]),
            "gs_host_flight_uplink": (None, [P, B, S]),
            "gs_host_flight_take_gyro_offset": (I, [P, D]),
            "gs_host_flight_restore_gyro_offset": (None, [P, D]),
            "gs_host_flight_mode": (U, [P]), "gs_host_flight_booting": (I, [P]),
            "gs_host_deframer_init": (None, [P]),
            "gs_host_deframer_feed": (S, [P, B, S, B, S]),
        }
        for name, (restype, argtypes) in signatures.items():
            function = getattr(lib, name)
            function.restype, function.argtypes = restype, argtypes
        _LIBRARY = lib
    return _LIBRARY


def _doubles(*values: float):
    return (ctypes.c_double * len(values))(*values)


def _floats(*values: float):
    return (ctypes.c_float * len(values))(*values)


def ahf_settings(settings) -> ctypes.Array:
    """groundstation's ``AhfSettings`` as the core's nine doubles (the order of gs_host.c's ahf_settings)."""
    s = settings
    return _doubles(s.lambda_max, s.lambda_min, s.lowpass, s.error_gain, s.gyro_overrange_rad_s, s.acc_min_g,
                    s.acc_deviation_max_g, s.acc_window_s, s.max_gap_s)


class Ahf32:
    """The core's onboard AHF (gs_ahf.c) alone: ``step`` returns (status, q (4), lambda, e_a, err) as floats;
    ``acc_dev_g`` is then the low-passed accelerometer deviation from 1 g (base.py's ``STATE_ACC_DEV``, ``Ahf._acc_dev``)."""

    def __init__(self, settings, q0=None):
        self._lib = lib = library()
        self._state = ctypes.create_string_buffer(lib.gs_host_sizeof_ahf())
        if lib.gs_host_ahf_init(self._state, ahf_settings(settings), None if q0 is None else _floats(*q0)) != 0:
            raise ValueError(f"the C AHF rejects the settings {settings}")
        self._out = (ctypes.c_float * 8)()

    def step(self, gyr_rad_s, acc_g, dt_s):
        status = self._lib.gs_host_ahf_step(self._state, _floats(*gyr_rad_s), _floats(*acc_g), dt_s, self._out)
        out = list(self._out)
        return status, out[:4], out[4], out[5], out[6]

    @property
    def acc_dev_g(self) -> float:
        return self._out[7]


class FlightCore:
    """The flight board's firmware core (gs_flight.c): register samples in, frames out, uplink commands."""

    def __init__(self, *, rate_hz: int, accel_fs_g: int, gyro_fs_dps: int, mounting: int, mode: int,
                 boot_calibration_s: float, fw_version: tuple[int, int, int], ahf, stored_gyro_offset_dps=None):
        """``stored_gyro_offset_dps``: the calibration the board kept over a reset (deg/s, sensor axes), or None."""
        self._lib = lib = library()
        self._state = ctypes.create_string_buffer(lib.gs_host_sizeof_flight())
        config = (ctypes.c_uint * 8)(rate_hz, accel_fs_g, gyro_fs_dps, mounting, mode, *fw_version)
        if lib.gs_host_flight_init(self._state, config, boot_calibration_s, ahf_settings(ahf)) != 0:
            raise ValueError("the C firmware core rejects this configuration")
        if stored_gyro_offset_dps is not None:
            lib.gs_host_flight_restore_gyro_offset(self._state, _doubles(*stored_gyro_offset_dps))
        self._out = ctypes.create_string_buffer(lib.gs_host_max_out())
        self._registers = (ctypes.c_int16 * 7)()
        self._offset = (ctypes.c_double * 3)()

    def sample(self, t_us: int, registers, battery_v: float, cpu_load_pct: float) -> bytes:
        """``registers``: acc x y z, gyr x y z, TEMP_OUT counts. Returns the frames to send."""
        self._registers[:] = registers
        n = self._lib.gs_host_flight_sample(self._state, t_us, self._registers, _doubles(battery_v, cpu_load_pct), self._out, len(self._out))
        return self._out.raw[:n]

    def uplink(self, frame: bytes) -> None:
        self._lib.gs_host_flight_uplink(self._state, frame, len(frame))

    def take_gyro_offset(self) -> list[float] | None:
        """deg/s to subtract from the gyro (the chip's offset registers), when a calibration has finished."""
        return list(self._offset) if self._lib.gs_host_flight_take_gyro_offset(self._state, self._offset) else None

    @property
    def mode(self) -> int:
        return self._lib.gs_host_flight_mode(self._state)

    @property
    def booting(self) -> bool:
        return bool(self._lib.gs_host_flight_booting(self._state))


class Deframer:
    """The bridge's serial-side deframer (gs_deframer.c): bytes in, whole intact frames out."""

    def __init__(self):
        self._lib = lib = library()
        self._state = ctypes.create_string_buffer(lib.gs_host_sizeof_deframer())
        lib.gs_host_deframer_init(self._state)

    def feed(self, data: bytes) -> bytes:
        out = ctypes.create_string_buffer(len(data) + 32)
        n = self._lib.gs_host_deframer_feed(self._state, data, len(data), out, len(out))
        return out.raw[:n]


def split_frames(data: bytes) -> list[bytes]:
    """Back-to-back frames (as the core returns them) one by one, by their length byte."""
    from firmware_protocol.spec import SPEC

    frames, i = [], 0
    while i < len(data):
        n = data[i + 1] + SPEC.header_bytes + SPEC.crc_bytes
        frames.append(data[i : i + n])
        i += n
    return frames
