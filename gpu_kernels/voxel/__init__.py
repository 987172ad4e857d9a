"""The GPU voxeliser both GI methods share: surfaces into area, albedo, normal and emission volumes."""
