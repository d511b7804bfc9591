"""Augmented reality (004): marker boards, camera intrinsics, tracking by ArUco markers and PnP, synthetic views
with known poses (the test data: real photographs are not available offline)."""
