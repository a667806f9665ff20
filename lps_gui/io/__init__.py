"""Files of SPEC 7 and the session folder: atomic writes, locks, sessions, boards, intrinsics, corners, results."""
