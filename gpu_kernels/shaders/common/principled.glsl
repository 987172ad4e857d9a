// SPDX-License-Identifier: GPL-3.0-or-later
// Principled BSDF's diffuse share, with no uniforms, so the camera's G-buffer (common/materials.glsl) and the
// viewport's fragment shader (viewport/surface.glsl) colour surfaces alike.
#pragma once

// Share of the base colour that Principled BSDF reflects diffusely, 1 − A_spec(roughness, μ = n·v), at IOR 1.5 and
// Specular IOR Level 0.5: Cycles scales the diffuse closure by (1 − albedo of the specular layer)
// (kernel/svm/closure.h, closure_layering_weight) and its Diffuse Color pass shows the scaled colour. Values are
// measured from Cycles 5.2.3's Diffuse Color pass (base 0.8); the μ = 0 row is the grazing limit (Fresnel → 1).
const float MU_ROWS[7] = float[](0.0, 0.087, 0.259, 0.5, 0.707, 0.866, 1.0);
const float ROUGH_COLS[6] = float[](0.0, 0.1, 0.25, 0.5, 0.75, 1.0);
const float DIFFUSE_SHARE[42] = float[](
    0.0,     0.0,     0.0,     0.0,     0.0,     0.0,
    0.37972, 0.40365, 0.59258, 0.81089, 0.90123, 0.93673,
    0.74670, 0.74811, 0.77558, 0.87651, 0.93345, 0.96122,
    0.91024, 0.91018, 0.91110, 0.93081, 0.95745, 0.97582,
    0.94950, 0.94944, 0.94898, 0.95284, 0.96740, 0.98179,
    0.95848, 0.95846, 0.95829, 0.96031, 0.97140, 0.98456,
    0.96000, 0.96000, 0.96011, 0.96262, 0.97320, 0.98621);

float principled_diffuse_share(float mu, float roughness) {
    mu = clamp(mu, 0.0, 1.0);
    roughness = clamp(roughness, 0.0, 1.0);
    int i = 0;
    while (i < 5 && mu > MU_ROWS[i + 1]) ++i;
    int j = 0;
    while (j < 4 && roughness > ROUGH_COLS[j + 1]) ++j;
    float ti = (mu - MU_ROWS[i]) / (MU_ROWS[i + 1] - MU_ROWS[i]);
    float tj = (roughness - ROUGH_COLS[j]) / (ROUGH_COLS[j + 1] - ROUGH_COLS[j]);
    float a = mix(DIFFUSE_SHARE[i * 6 + j], DIFFUSE_SHARE[i * 6 + j + 1], tj);
    float b = mix(DIFFUSE_SHARE[(i + 1) * 6 + j], DIFFUSE_SHARE[(i + 1) * 6 + j + 1], tj);
    return mix(a, b, ti);
}
