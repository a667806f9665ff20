"""GRBL 1.1: code tables, protocol parsing, the pyserial driver and a pty emulator."""
