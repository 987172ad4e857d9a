# SPDX-License-Identifier: GPL-3.0-or-later
"""Direct light: geometry upload, shadow maps, the G-buffer and the Diffuse Direct pass."""
