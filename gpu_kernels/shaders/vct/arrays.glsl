// SPDX-License-Identifier: GPL-3.0-or-later
// Access to arrays of six textures / images by a non-constant index, through switches whose cases index with
// constants. Why: GLSL only allows dynamically uniform indices into opaque arrays, and llvmpipe (Mesa 22) takes the
// index from one SIMD lane: once lanes diverge (an early return for empty voxels or background pixels), a loop
// index could pick another lane's texture (measured: vct_inject lost a third of the occupied voxels).
#pragma once

#define VCT_FETCH6(fn, arr) vec4 fn(int i, ivec3 c, int lod) { switch (i) { \
    case 0: return texelFetch(arr[0], c, lod); case 1: return texelFetch(arr[1], c, lod); \
    case 2: return texelFetch(arr[2], c, lod); case 3: return texelFetch(arr[3], c, lod); \
    case 4: return texelFetch(arr[4], c, lod); default: return texelFetch(arr[5], c, lod); } }

#define VCT_STORE6(fn, arr) void fn(int i, ivec3 c, vec4 x) { switch (i) { \
    case 0: imageStore(arr[0], c, x); break; case 1: imageStore(arr[1], c, x); break; \
    case 2: imageStore(arr[2], c, x); break; case 3: imageStore(arr[3], c, x); break; \
    case 4: imageStore(arr[4], c, x); break; default: imageStore(arr[5], c, x); break; } }
