// SPDX-License-Identifier: GPL-3.0-or-later
// The cached transport's receivers' irradiance after a solve, written into the six volumes the flux lookup filters
// (lpv/lighting.glsl MODE_RECEIVER_VOLUMES; lpv/receivers.py LightVolumes): receiver i's front and back records at
// its fine voxel, in the volumes of its axis. Voxels without a receiver stay as they were made: zero.
layout(local_size_x = 64) in;
layout(std430, binding = 6) readonly buffer ReceiverRecords { vec4 records[]; };  // per receiver: front, back
layout(std430, binding = 7) readonly buffer ReceiverCells { ivec4 cells[]; };     // per receiver: voxel, axis
layout(rgba32f, binding = 0) uniform writeonly image3D u_x_front;
layout(rgba32f, binding = 1) uniform writeonly image3D u_x_back;
layout(rgba32f, binding = 2) uniform writeonly image3D u_y_front;
layout(rgba32f, binding = 3) uniform writeonly image3D u_y_back;
layout(rgba32f, binding = 4) uniform writeonly image3D u_z_front;
layout(rgba32f, binding = 5) uniform writeonly image3D u_z_back;
uniform int u_count;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_count) return;
    ivec4 c = cells[i];
    vec4 front = records[2 * i], back = records[2 * i + 1];
    // Image arrays may only be indexed uniformly (GLSL 4.30): one image per axis and side.
    if (c.w == 0) {
        imageStore(u_x_front, c.xyz, front);
        imageStore(u_x_back, c.xyz, back);
    } else if (c.w == 1) {
        imageStore(u_y_front, c.xyz, front);
        imageStore(u_y_back, c.xyz, back);
    } else {
        imageStore(u_z_front, c.xyz, front);
        imageStore(u_z_back, c.xyz, back);
    }
}
