"""The simulator's truth: stage error models, the rig, simulated views; no estimation model imports it."""
