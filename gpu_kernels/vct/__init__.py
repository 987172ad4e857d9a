# SPDX-License-Identifier: GPL-3.0-or-later
"""Voxel Cone Tracing (Crassin et al. 2011; Freed 2018): voxelize → inject direct light → mipmap → bounce → trace.

Passes (vct/passes.py runs them through the pass cache):
  vct_voxelize  the shared GPU voxelizer (voxel/voxelize.py) on a grid padded so every mip level nests exactly:
                the surfaces' areas and normals;
  vct_albedo    each voxel face's albedo, from the surface points whose light leaves through it (vct/inject.py,
                vct/face_albedo.glsl): a material's colour edit re-makes this, not the voxels or the light;
  vct_inject    surface points rasterised along their dominant axis and lit by every light exactly as the Diffuse
                Direct pass lights pixels (direct/eval.glsl), averaged into six faces per voxel: the light arriving
                at the surfaces whose light leaves through each face, its coverage and where those surfaces lie
                (vct/inject*.glsl); the lamps, the emissive meshes and the sky each in a pass of its own, summed and
                multiplied by the faces' albedo, so an edit re-injects only its part (vct/parts.py);
  vct_mipmap    the filtered radiance volumes: isotropic (mean of children) or anisotropic (six directions,
                composited front to back, plus where each texel's surfaces lie along each axis, so a cone skips
                surfaces behind where it started) (vct/mipmap.glsl, Freed 2018, §4.4);
  vct_bounce    bounces − 1 gathers at the voxel faces, each followed by a re-mip (vct/bounce.glsl);
  vct_trace     diffuse cones per G-buffer pixel (or per s × s block, indirect_scale) → Diffuse Indirect and voxel
                AO (vct/trace.glsl, Freed 2018, §4.5.2); with anisotropic volumes each cone is a bundle of sub-rays
                that meet surfaces where they cross them (vct/crossing.glsl);
  vct_upsample  reduced-resolution results back to every pixel, depth- and normal-aware (vct/upsample.py;
                Kircher and Lawrance 2009's inferred lighting);
  vct_accumulate  temporal average of jittered cone sets (vct/temporal.py);
  vct_specular  one glossy cone per pixel → Glossy Indirect (vct/specular.py).

Every scale is derived; the shaders' comments give the derivations (self-occlusion bound, step opacity, anisotropic
optical depth, the layer test, sub-rays), `cone_table` and `subray_radius` give the cones'. The world is a light
(common/lights.py: the sky light, shadowed by the real triangles): its direct light is Diffuse/Glossy Direct as in
Cycles, its bounce enters the voxels through their injection like any light's, and no cone adds the world it
reaches — a voxel's partial opacity would let the sky through walls thinner than a voxel.
"""
