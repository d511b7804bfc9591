"""A long session in one process (issue 19): edits and scene variants leave memory bounded — the second half
adds no more than noise to the first half's peak — the program cache within its bound, the GL error flag
clean. The full curve is `reflets bench soak` (1,000 edits)."""

import pytest

from reflets.bench.soak import soak
from reflets.gpu import programs


@pytest.mark.slow
def test_a_long_session_stays_within_a_budget():
    rows = soak(edits=96, block=16)  # six blocks: three against three
    first = max(r["rss_mb"] for r in rows[1 : len(rows) // 2 + 1])
    second = max(r["rss_mb"] for r in rows[len(rows) // 2 + 1 :])
    assert second - first < 150, rows  # `reflets bench soak`: +18 MB over 1,000 edits, blocks oscillating by ±70 MB
    assert all(r["programs"] <= programs.MAX_PROGRAMS for r in rows)
    assert all(r["gl_error"] == "GL_NO_ERROR" for r in rows)
    others = [r["gl_objects"] - r["programs"] for r in rows]  # every GL object but the cached programs
    assert max(others) - min(others) <= 8, rows
