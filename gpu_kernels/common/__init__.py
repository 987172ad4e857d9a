# SPDX-License-Identifier: GPL-3.0-or-later
"""CPU-side pieces several stages share: the camera, the voxel grid, the light records, the bounce tail, and what a
GI method returns."""
