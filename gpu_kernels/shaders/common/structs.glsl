// SPDX-License-Identifier: GPL-3.0-or-later
// Buffer records shared by several programs. Each mirrors a numpy dtype field for field (std430: vec4 members only,
// so the offsets are 16-byte aligned on every driver): Vpl ↔ lpv/gather.py VPL_DTYPE. The light, view and
// polygon records live with their evaluation in common/lights.glsl.
#pragma once

// A virtual point light (Keller 1997, "Instant Radiosity"): an RSM texel block or a cluster of surface voxels.
struct Vpl {
    vec4 position;  // xyz, w = 1
    vec4 normal;    // xyz unit normal, w = area (m²) of the source (0 where a point)
    vec4 flux;      // rgb (W)
};
