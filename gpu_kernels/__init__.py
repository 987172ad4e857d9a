# SPDX-License-Identifier: GPL-3.0-or-later
"""Bounce GI's pure GPU core: Scene in, Cycles-named passes and timings out. Never imports bpy."""
