"""Camera intrinsics from varied-pose board views: calibration, refinement, cross-validation of lens models."""
