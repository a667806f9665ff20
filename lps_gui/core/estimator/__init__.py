"""From observations to one LpsEstimate: options and result types, the solve, outlier rounds, per view, targets."""
