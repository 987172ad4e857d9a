# SPDX-License-Identifier: GPL-3.0-or-later
"""Ground truth from Cycles: references rendered with settings that make comparisons exact, and cached."""
