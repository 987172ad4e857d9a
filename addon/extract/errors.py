# SPDX-License-Identifier: GPL-3.0-or-later
"""The one error extraction raises on purpose (its own module so every extractor can raise it)."""


class ExtractError(ValueError):
    """The Blender scene cannot be turned into a renderable Scene; the message is for the user."""
