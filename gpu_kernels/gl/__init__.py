# SPDX-License-Identifier: GPL-3.0-or-later
"""GL plumbing: the worker thread and its context, shader preprocessing and programs, the pass cache, and the
binding helpers every stage uses."""
