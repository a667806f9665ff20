"""The camera dock: live preview with the detection overlay, and the intrinsics calibration panel."""
