"""Test-wide settings: Qt offscreen, seeded randomness is per test."""
import os

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
