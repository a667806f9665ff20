"""The capture dock: plans (line, planar, stitched, targets), report set-up, live results while capturing."""
