# SPDX-License-Identifier: GPL-3.0-or-later
"""The surface atlas: light computed per surface point rather than per pixel, for the viewport (atlas.py)."""
