"""The C firmware core is checked wherever a C compiler exists; elsewhere its tests skip, saying why."""

import pytest

from firmware_protocol.reference import host


@pytest.fixture(scope="session")
def c_core():
    """The core's host library, built (with -Werror) into a temporary cache; a compile error fails."""
    if host.compiler() is None:
        pytest.skip("no C compiler (cc, gcc or clang) on this machine: the C firmware core is not checked")
    return host.library()
