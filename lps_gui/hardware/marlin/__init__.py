"""Marlin 2.x firmware (3D-printer and CNC gantries): the G-code driver and its pty emulator."""
