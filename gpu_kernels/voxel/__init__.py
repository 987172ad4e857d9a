# SPDX-License-Identifier: GPL-3.0-or-later
"""The GPU voxeliser both GI methods share: surfaces into area, albedo, normal and emission volumes."""
