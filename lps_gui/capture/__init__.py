"""The capture engine: plans run on a stage and a camera into a session (settle, locks, compensation, resume),
and the operator's session set-up both faces build."""
