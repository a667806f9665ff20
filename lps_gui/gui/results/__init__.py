"""The results dock: estimation, every results tab and plot, the clicked view, planar results."""
