"""The capture engine: plans run on a stage and a camera into a session, with settle, locks, compensation and resume."""
