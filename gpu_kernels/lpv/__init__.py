# SPDX-License-Identifier: GPL-3.0-or-later
"""Light Propagation Volumes (Kaplanyan and Dachsbacher 2010; Kaplanyan 2009; Elvek 2012; Olovsson and Doggett
2013): RSMs → VPL injection → propagation with fuzzy occlusion →
absorbed light → irradiance. Every scale is derived, none tuned (see the shaders' comments):

- RSM texel → VPL flux Φ = albedo × irradiance × texel area (lpv/inject.glsl), so injection is independent of
  the RSM resolution; world light is the sky light's RSMs (common/lights.py), like any light's;
- a VPL is the Lambertian intensity (Φ/π)·max(0, n·ω) on 2-band SH, in the cell half a cell in front of it;
- propagation conserves flux exactly in empty space (far face 0.4006696846 sr + 4 side faces 0.4234313544 sr
  = 2π/3 per neighbour); negative lobes propagate as they are unless `clamp_negative` (which adds energy);
- lookup (default "flux"): a surface's irradiance is the flux fuzzy occlusion stopped at it, per area — summed
  over all surfaces this is exactly the injected flux that did not leave the grid (lpv/occlusion.py); the
  classic lookup, SH intensity convolved with the cosine / cell², is `lookup="intensity"`;
- bounces: absorbed light × albedo is injected again;
- transport (default "transfer", lpv/transfer.py): every surface voxel gathers the light of clusters of surface
  voxels directly, with fuzzy visibility, through a kernel cached per geometry (light, material and world edits
  re-run no visibility); "gather" (lpv/gather.py) re-makes its VPL lists every bounce; "propagate" is the classic
  LPV above — the face scheme turns light sideways within a few cells. World light bounces in all three.

Iterations stop adaptively once a step moves less than `epsilon` of the injected flux.
"""
