"""Zaber's library looks devices up in Zaber's online device database; the tests point it at a closed local port so
that every run, with or without a network, takes the same path (the manual's units) without waiting for a lookup.
Its store of past lookups (in ~/.cache) is off: no run reads what an earlier one left, and the two pytest-xdist
workers never write one file at once."""
from __future__ import annotations

import pytest


@pytest.fixture(autouse=True, scope="session")
def _zaber_device_db_offline():
    from zaber_motion import DeviceDbSourceType, Library

    Library.set_device_db_source(DeviceDbSourceType.WEB_SERVICE, "http://127.0.0.1:9/device-db")
    Library.disable_device_db_store()
    yield
