"""GRBL 1.1: code tables, $N settings over the simulated machine, protocol parsing, the pyserial driver and a pty emulator."""
