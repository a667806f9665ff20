"""Capture plans and rig planning: stops, limits, segments, presets, target rows, two-depth constellations."""
