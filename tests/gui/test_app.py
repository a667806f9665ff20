"""The application object: names and icon (the desktop entry matches them)."""
import pytest

pytestmark = pytest.mark.gui


def test_the_application_carries_its_icon_in_every_size():
    from lps_gui.gui.app import app_icon, make_app

    app = make_app([])
    icon = app_icon()
    assert not icon.isNull() and len(icon.availableSizes()) >= 5
    assert not app.windowIcon().isNull()
