"""The reference firmware (C, beside the protocol it speaks); see docs/firmware.md.

``core/`` is the portable C99 core (onboard AHF, frames, commands, the bridge's deframer), ``host/``
its plain-argument entry points for the host, ``stm32/`` the STM32F103 flight board and bridge
ports. ``host.py`` builds the core into a shared library with the system C compiler and wraps it
with ctypes, so the ground station's simulator and tests run the real firmware code.
"""
