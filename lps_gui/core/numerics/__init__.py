"""Linear algebra the solvers share: the block arrowhead, Schur steps, covariances, robust outlier statistics."""
