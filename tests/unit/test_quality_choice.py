# SPDX-License-Identifier: GPL-3.0-or-later
"""addon/quality.render_settings_for: a table row becomes the RenderSettings it was measured with — except that an
LPV row of the per-bounce gather runs as the cached transfer (the same kernel, kept across edits)."""
from bounce_gi.addon.quality import Choice, render_settings_for


def test_a_gather_row_runs_as_the_cached_transfer_and_keeps_its_other_settings():
    row = Choice("lpv", {"resolution": 16, "bounces": 3, "transport": "gather", "no_such_key": 1}, 0.8, 0.06,
                 "lpv 16", "test")
    s = render_settings_for(row, 40, 30)
    assert (s.method, s.width, s.height) == ("lpv", 40, 30)
    assert (s.lpv.transport, s.lpv.resolution, s.lpv.bounces) == ("transfer", 16, 3)
    propagate = Choice("lpv", {"transport": "propagate"}, 1.0, 0.3, "lpv propagate", "test")
    assert render_settings_for(propagate, 40, 30).lpv.transport == "propagate"
