// SPDX-License-Identifier: GPL-3.0-or-later
// Light and shadow-view records shared by the lighting shaders. Each struct mirrors a numpy dtype in
// gpu_kernels/common/lights.py field for field (std430); tests/gpu/test_light_buffers.py checks the offsets.
#pragma once

#define LIGHT_SUN 0
#define LIGHT_POINT 1
#define LIGHT_SPOT 2
#define LIGHT_POLYGON 3   // area lights and emissive triangles
#define LIGHT_SKY 4       // the world: constant radiance from every direction, shadowed from many directions
#define MAX_POLYGON_VERTICES 34  // a 32-gon plus one vertex per clipping plane, with margin

struct GpuLight {
    vec4 color_type;      // rgb: sun irradiance (W/m²) | point/spot intensity (W/sr) | polygon radiance; w: type
    vec4 position;        // xyz: position (point/spot) or polygon centroid; w: r² of a soft-falloff light
    vec4 direction;       // xyz: unit direction the light points along (sun/spot/polygon normal); w: cos half spot angle
    vec4 params;          // x: spot smoothstep scale; y: first shadow view; z: shadow sample count; w: views per sample
    vec4 polygon;         // x: first polygon vertex; y: vertex count; z: two-sided (1) or one-sided (0);
                          // w: 0 one polygon, 1 a list of y/4 triangles (an emitter cluster, common/emitters.py):
                          //    per triangle three vertices, then its radiance relative to color_type.rgb
};

struct ShadowView {
    mat4 view_projection;
    vec4 tile;            // atlas uv rectangle: xy origin, zw size
    vec4 origin;          // xyz: eye position (perspective) ; w: 1 if orthographic
    vec4 info;            // x: texel world size at unit distance (perspective) or absolute (ortho); y: PCF radius in texels; w: index of its light;
                          // z: far distance (perspective: stored depth = distance / far)
    vec4 emitter;         // polygon lights' sample points: xyz the normal the light emits along there, w the share
                          // of the light's area the point stands for (polygon_visibility's weights); else 0
};

layout(std430, binding = 0) readonly buffer LightBuffer { GpuLight lights[]; };
layout(std430, binding = 1) readonly buffer ShadowViewBuffer { ShadowView shadow_views[]; };
layout(std430, binding = 2) readonly buffer PolygonBuffer { vec4 polygon_vertices[]; };
