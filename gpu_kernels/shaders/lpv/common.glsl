// SPDX-License-Identifier: GPL-3.0-or-later
// Two-band spherical harmonics and the LPV grid (Kaplanyan and Dachsbacher 2010; Kaplanyan 2009). SH basis and
// conventions: docs/conventions.md; the clamped-cosine coefficients are Ramamoorthi and Hanrahan 2001's.
#pragma once

// Basis (real SH with Sloan 2008's sign convention): Y00 = 0.282095, Y1-1 = −0.488603·y, Y10 = 0.488603·z,
// Y11 = −0.488603·x.
vec4 sh_basis(vec3 d) {
    return vec4(0.282094792, -0.488602512 * d.y, 0.488602512 * d.z, -0.488602512 * d.x);
}

// Projection of the clamped cosine lobe max(0, n·ω): (√π/2, −√(π/3)·n.y, √(π/3)·n.z, −√(π/3)·n.x).
// Its integral over the sphere is π, so (Φ/π)·lobe is the intensity of a Lambertian emitter of flux Φ.
vec4 sh_clamped_cosine(vec3 n) {
    return vec4(0.886226925, -1.023326708 * n.y, 1.023326708 * n.z, -1.023326708 * n.x);
}

// Flux of an intensity distribution given by SH coefficients c: ∫ c·Y dω = c0 · 2√π.
float sh_flux(vec4 c) {
    return c.x * 3.544907702;
}

struct LpvGrid {
    vec3 origin;   // world position of the min corner
    float cell;    // cell size (m)
    ivec3 size;
};

ivec3 lpv_cell(LpvGrid g, vec3 p) {
    return ivec3(floor((p - g.origin) / g.cell));
}

bool lpv_inside(LpvGrid g, ivec3 c) {
    return all(greaterThanEqual(c, ivec3(0))) && all(lessThan(c, g.size));
}

int lpv_index(LpvGrid g, ivec3 c) {
    return (c.z * g.size.y + c.y) * g.size.x + c.x;
}
