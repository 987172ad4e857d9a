# SPDX-License-Identifier: GPL-3.0-or-later
"""Results on disk and their errors: multi-layer EXR I/O and the error metrics against Cycles."""
