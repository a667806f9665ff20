"""`lps plan-rig`: before a capture, the rig's view and sigma, a row of targets, a two-depth constellation."""
