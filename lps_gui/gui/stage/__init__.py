"""The stage dock: sources, connection, the declared capabilities' controls, DRO, console, controller thread."""
