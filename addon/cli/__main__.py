# SPDX-License-Identifier: GPL-3.0-or-later
"""`python -m bounce_gi.addon.cli`: the `bounce-gi` console script without the installed entry point."""
import sys

from . import main

sys.exit(main())
