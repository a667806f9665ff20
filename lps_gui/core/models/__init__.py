"""The stage models fitted to the corners: line, plane, 6-DOF poses, constant orientation, targets, poses out."""
