"""CPU-side pieces several stages share: the camera, the voxel grid, the light records, the bounce tail, and what a
GI method returns."""
