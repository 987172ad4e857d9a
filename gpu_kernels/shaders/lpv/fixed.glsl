// SPDX-License-Identifier: GPL-3.0-or-later
// Fixed-point accumulation of LPV injections (no float atomics here): 12 ints per cell, RGB × 4 SH coefficients,
// scaled by u_fixed_scale (lpv/state.py: FIXED_RANGE / a bound of the flux, so sums stay below 2³¹).
#pragma once
#include "lpv/common.glsl"

layout(std430, binding = 4) buffer LpvAccum { int accum[]; };
uniform float u_fixed_scale;

void add_fixed(int base, vec4 c) {
    atomicAdd(accum[base + 0], int(round(c.x * u_fixed_scale)));
    atomicAdd(accum[base + 1], int(round(c.y * u_fixed_scale)));
    atomicAdd(accum[base + 2], int(round(c.z * u_fixed_scale)));
    atomicAdd(accum[base + 3], int(round(c.w * u_fixed_scale)));
}

// A Lambertian emitter of flux Φ (RGB) with normal n: intensity (Φ/π)·max(0, n·ω) on 2-band SH, added to the cell
// half a cell in front of p (Elvek 2012, §3.3: "offset half a cell size in the direction of its normal").
void inject_lambertian(LpvGrid g, vec3 p, vec3 n, vec3 flux) {
    if (max(flux.r, max(flux.g, flux.b)) <= 0.0) return;
    ivec3 c = lpv_cell(g, p + n * 0.5 * g.cell);
    if (!lpv_inside(g, c)) return;
    vec4 lobe = sh_clamped_cosine(n) / 3.14159265358979;
    int base = lpv_index(g, c) * 12;
    add_fixed(base + 0, lobe * flux.r);
    add_fixed(base + 4, lobe * flux.g);
    add_fixed(base + 8, lobe * flux.b);
}
