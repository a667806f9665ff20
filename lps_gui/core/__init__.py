"""Pure math, no I/O: geometry, numerics, models, the estimator, intrinsics, metrology, planning and the simulator's truth."""
