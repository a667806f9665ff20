"""The sections of results.json built from one estimate: board plane, planar, error motions, ASME, targets, uncertainty."""
