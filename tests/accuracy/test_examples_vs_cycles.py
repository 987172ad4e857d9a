# SPDX-License-Identifier: GPL-3.0-or-later
"""The example scenes like users' (issue 17) against their committed Cycles references — regression bounds.

Each scene of examples/references (examples.scenes.USER_SCENES) is rendered with both methods' defaults, as
`bounce-gi render` would, and every pass is compared with the committed two-seed Cycles reference (8 bounces,
160×120, the samples its JSON says; examples/references/make_references.py renders them with
addon/reference/cycles.py). Cycles is never rendered here. The work runs in one subprocess,
tests/support/examples_table.py, which also prints the whole table and the BOUNDS below:

    python tests/support/examples_table.py            # the markdown table and a BOUNDS dict to paste here

BOUNDS, measured with that command (commit and date in the comment above it): rel-L1 per scene × method × pass over the pixels
that hit geometry in both renders; a bound = measured + 2 × the pass's noise floor + 0.001, rounded up to 3
decimals. The margin: the noise floor f (half the rel-L1 between the reference's seeds) is the size of the
reference's own error, so a reference rendered again (other seeds, another Cycles build) moves our rel-L1 by at most
rel-L1(old, new) ≈ √2·f (triangle inequality; 2f leaves room for f's own spread); 0.001 covers the float16 storage
(2⁻¹¹ relative) and llvmpipe rounding. Our renderer is deterministic on one driver, so any change of our output
larger than that fails. Where a measurement meets the issue's target (Combined ≤ 0.08, Diffuse Indirect ≤ 0.15,
Diffuse Direct ≤ 0.02, Glossy Direct ≤ 0.10) the bound is the target if that is lower. A pass our renderer does not
write, or writes as 0, counts as 1.0, and its bound is 1.0 exactly. "Diffuse Color match" (the share of pixels within 0.01 of Cycles' in every channel, target ≥ 98%) is a
lower bound: measured − 2 × the share of pixels whose Diffuse Color differs between the seeds − 0.001, or 0.98
where met. "Diffuse Light" is Diffuse Direct + Indirect (Cycles counts world light as direct, and so do we since the sky
light: the sum is kept as a check of the total).

After a renderer change: run the command, check the table, paste the printed BOUNDS (lower bounds are the point).
"""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from support.examples_table import MATCH, TARGETS

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
from examples import references  # noqa: E402

# Measured by `python tests/support/examples_table.py` on 416849a + the glossy layers' energy in the light that bounces
# on (common/principled.transport_albedo: voxels and the LPV's shadow-map texels reflect diffuse + glossy),
# 2026-12-02, on llvmpipe, against the references committed with the scenes; rounded with the rule in the docstring.
# The LPV rows re-measured 2026-12-02 after: the RSM counting each shadow-cube face's own texels only (lpv/inject.glsl
# cube_share); the transfer's near field as exact rectangles (lpv/gather.glsl, now polygon_kernel); the RSM binned per
# texel into its own voxel's side, and none from a surface that faces nothing (lpv/clusters.bin_flux, own_side,
# TEXEL_RECORDS); a voxel's surfaces presenting at most one layer's area (lpv/occlusion.layer_area).
# Both methods re-measured 2026-12-02 (seventh session) after: the sky's glossy share weighted by the GGX lobe with
# its Fresnel (direct/light.glsl sky_shares); the RSM's depth linear (lpv/rsm.glsl: a rug 1 mm over a floor no
# longer z-fights); the LPV's voxels keeping an albedo per side (voxel/voxelize.py sides=True).
# The LPV rows re-measured 2026-12-03 after the cached transport's receivers per dominant axis, at their surfaces'
# centroids (lpv/receivers.py), and the two-layer crossings (lpv/crossings.py): most scenes closer to Cycles,
# default_principled and metals further (Diffuse Indirect 0.107 -> 0.120 and 0.150 -> 0.182: 3% and 10% too bright).
# 2026-12-04: area lights' soft shadows by backprojection onto each sample's patch (direct/eval.glsl
# patch_visibility) moved metals' VCT Diffuse Indirect from 0.1487 to 0.1502 (the voxels are lit like the pixels):
# within its noise floor (0.032), but past the 0.15 target it had met, so it is held by the rule instead; the
# product shot's rows tightened to the rule after it (Diffuse Direct 0.034 -> 0.022, Combined 0.048 -> 0.036).
# 2026-12-04 (second session): the sky's shares averaged over each pixel's penumbra on its own surface
# (direct/sky_filter.glsl) re-measured the four sky-lit scenes: Diffuse Direct window_room 0.093 -> 0.070,
# thin_walls 0.180 -> 0.111, furnished 0.0198 -> 0.0191, outdoor 0.0144 (unchanged); Glossy Direct 0.159 -> 0.138
# and 0.297 -> 0.220 in the two rooms; outdoor's Combined rose 0.0433 -> 0.0444 (LPV) and 0.0482 -> 0.0499 (VCT),
# so its bounds rose with it.
# 2026-12-05: the VCT rows re-measured after the bounce gathers stopped reading texels wider than 1/16 of the grid
# (vct/volumes.py gather_levels: coarser texels straddle a room's walls and let cones out of it): Combined / Diffuse
# Indirect many_lights 0.109 / 0.167 -> 0.090 / 0.140, thin_walls 0.100 / 0.112 -> 0.075 / 0.086, rug_room 0.059 /
# 0.113 -> 0.043 / 0.082; the others within 0.002.
# 2026-12-05 (later): the VCT rows re-measured after the per-pixel sub-rays stopped stepping over surfaces that are
# not aligned with the grid (vct/crossing.glsl: each surface's depth read at both ends of a step, one step's coverages
# added, the finer read in the sub-ray's own column). Diffuse Indirect: outdoor 0.275 -> 0.237, product_shot 0.138 ->
# 0.128; metals 0.151 -> 0.180 (1.07x -> 1.11x Cycles: its spheres, half invisible to the cones before, now bounce
# their light, and the transport treats a metal's reflection as diffuse), many_lights 0.140 -> 0.148; others within
# 0.005. The closed sphere and the turned room of tests/gpu/test_vct_off_grid.py are what it was for.
# 2026-12-05 (stop 36): the LPV rows re-measured after the transfer's near field took every planar cluster as the
# octagon its surfaces span in its own plane, clipped into any convex piece by the receiver's plane (lpv/clusters.
# polygons, lpv/gather.glsl polygon_kernel; before: axis-plane rectangles cut into quads only). Diffuse Indirect
# (DI / Cycles): product_shot 0.135 -> 0.109 (0.95 -> 0.99), textured 0.080 -> 0.066, cornell_animated 0.052 -> 0.045;
# worse where we were already too bright: metals 0.182 -> 0.202 (1.10 -> 1.13: a metal's reflection bounces as if
# diffuse), default_principled 0.120 -> 0.129 (1.03 -> 1.07), lamp_room 0.091 -> 0.098 (1.07 -> 1.08); others within
# 0.002. A closed box turned 30° is what it was for (tests/gpu/test_lpv_transfer.py: 0.931 -> 0.967 of its exact
# irradiance).
# 2026-12-05 (stop 37): the sky-lit scenes re-measured after the sky's shadow maps went from 384 directions × 192² to
# 576 × 224² (common/lights.ShadowSettings; benchmarks/results/llvmpipe/sky.md), window_room against its new
# 16384-spp reference (Diffuse Direct noise floor 0.021 -> 0.003). Diffuse Direct / Glossy Direct: window_room
# 0.066 / 0.134 -> 0.059 / 0.096 (both against the new reference), furnished 0.0191 / 0.030 -> 0.0180 / 0.028,
# outdoor 0.0142 / 0.043 -> 0.0124 / 0.040; outdoor's LPV Diffuse Indirect 0.219 -> 0.227 (each sky direction's
# RSM view is coarser), so its bound rose with it. Then, area lights' sample cubes at 384² a face instead of 256²
# (ShadowSettings.area_cube_resolution: their soft shadows are backprojected from those texels): Diffuse Direct
# product_shot 0.0218 -> 0.0181 (the target met), furnished 0.0180 -> 0.0150, cornell_animated 0.0097 -> 0.0087;
# every scene re-measured. thin_walls against its new 16384-spp reference (Diffuse Direct floor 0.037 -> 0.005):
# Diffuse Direct 0.085, Glossy Direct 0.199, Diffuse Indirect 0.045 / 0.044.
# 2026-12-06: the VCT rows re-measured with the diffuse cones traced at every other pixel and upsampled (VctSettings.
# indirect_scale 2, now the default): every pass within 0.004 of the trace at every pixel (Diffuse Indirect metals
# 0.183 -> 0.179, outdoor 0.238 -> 0.239, many_lights 0.148 -> 0.148, cornell_animated 0.094 -> 0.093), a few bounds
# up by 0.001-0.002 with them.
# 2026-12-06 (later): lamp_room and furnished re-measured after closed emitters emit outwards only (their inner side's
# cubes given to more points on the outer side, common/emitters.py) and emitters stopped lighting RSM texels on their
# own surface (light_eval.glsl SELF_PLANE). lamp_room LPV / VCT: Diffuse Direct 0.028 -> 0.023, Glossy Direct 0.026
# -> 0.024, LPV Diffuse Indirect 0.098 -> 0.066 (1.08 -> 0.98 of Cycles'), Combined 0.055 -> 0.048 (VCT 0.052 ->
# 0.052); worse: LPV Glossy Indirect 0.295 -> 0.323, VCT 0.246 -> 0.251. furnished within 0.001 (Diffuse Direct
# 0.0154 -> 0.016). The other scenes have no closed emitter and did not move.
# 2026-12-06 (stop 39): lamp_room and furnished re-measured with 256 emitter cubes instead of 64, their faces shrunk
# to share 64 cubes' texels (common/lights.emitter_cube_resolution: 128² each here). lamp_room LPV / VCT: Diffuse
# Direct 0.023 -> 0.017 (the target met), Combined 0.048 -> 0.045 / 0.052 -> 0.047, VCT Diffuse Indirect 0.083 ->
# 0.080; furnished within 0.002 (Diffuse Direct 0.016 both). The other scenes have no emissive mesh.
# 2026-12-06 (stop 41): the VCT rows re-measured with 16 diffuse cones × 5 sub-rays per pixel (VctSettings; 9 × 7
# before, about the same trace time): Diffuse Indirect metals 0.179 -> 0.142 and many_lights' Combined 0.094 -> 0.066
# (both targets met now), many_lights' Diffuse Indirect 0.148 -> 0.093 (0.86 -> 0.92 of Cycles'), outdoor 0.239 ->
# 0.219, default_principled 0.084 -> 0.072; worse: lamp_room Diffuse Indirect 0.080 -> 0.087, Combined 0.047 -> 0.052.
# 2026-12-06 (stop 42): the LPV rows re-measured after a cell holding flat axis-facing layers of two or three axes (a
# floor and the foot of a wall) stopped being taken for their mean plane, tilted across the corner (lpv/crossings.py;
# tests/gpu/test_lpv_near_field.py: the floor at a block's foot 0.30 -> 0.999 of its view factor). Diffuse Indirect
# (DI / Cycles): many_lights 0.065 -> 0.056, furnished 0.110 -> 0.101, metals 0.201 -> 0.197; worse: thin_walls 0.045
# -> 0.054 (1.01 -> 1.04 of Cycles': dark lines along its floors' junctions had hidden light too bright elsewhere),
# outdoor 0.227 -> 0.234; the others within 0.001. Then a cluster whose mean normal lies along an axis stopped being
# taken as flat whatever its normals' spread (lpv/clusters.py polygons: a curved cap, as a square in its mean plane,
# lit the outside of its own surface from within): metals 0.197 -> 0.167 (1.14 -> 1.09 of Cycles'),
# default_principled 0.125 -> 0.120; worse: product_shot 0.100 -> 0.106 (its curved backdrop's clusters as quarter
# discs), textured 0.065 -> 0.068. The LPV's Glossy Indirect (read from the same light along the reflected direction)
# moved with them: its bounds rose by 0.005-0.011 in thin_walls, outdoor, product_shot and window_room.
# 2026-12-06 (stop 43): the LPV rows re-measured after a receiver cut by a one-sided wall in its own voxel (a floor
# running on under a closed box, the box's bottom with it) is kept on the side the wall faces (lpv/wall_sides.py;
# tests/gpu/test_lpv_near_field.py: the ground at a building's foot 0.00 -> 0.98 of its view factor). Diffuse
# Indirect: default_principled 0.120 -> 0.114, many_lights 0.056 -> 0.050, thin_walls 0.054 -> 0.049, outdoor 0.234
# -> 0.225, metals 0.167 -> 0.164, product_shot 0.106 -> 0.104; worse: window_room 0.068 -> 0.090 (1.02 -> 1.07 of
# Cycles': a cluster of its sunlit floor had its centre under the low table, whose top hid that light from the room;
# out from under it, the light of its glossy wood floor, which a VPL sends out diffusely, shows: with that floor
# made matte in both renderers the room reads 1.03 of Cycles', 0.99 before), cornell_animated 0.045 -> 0.048 (the
# floor under its blocks reflected as if lit), furnished 0.101 -> 0.104.
# Then a cluster's record and octagon from its core only (lpv/clusters.py _group: a detached bit joined to a
# cluster, a tree's crown to a façade at a town block's scale, pulled its octagon off the façade's plane and over
# the gap): Diffuse Indirect outdoor 0.225 -> 0.200 (the façades facing the camera 0.83 -> 0.87 of Cycles'), metals
# 0.164 -> 0.159, furnished 0.104 -> 0.100, thin_walls 0.049 -> 0.047; worse: default_principled 0.114 -> 0.118,
# textured 0.066 -> 0.070, product_shot 0.104 -> 0.106.
# Then up to twice the clusters where clusters × surface voxels stay within a large room's (LpvSettings
# transfer_pairs: 1024 in the six scenes of under 12 000 surface voxels, 531-574 in furnished, thin_walls and
# window_room, 512 in the others): Diffuse Indirect outdoor 0.200 -> 0.128 and metals 0.159 -> 0.132 (both targets
# met now), default_principled 0.118 -> 0.099, textured 0.070 -> 0.050, many_lights 0.050 -> 0.047, thin_walls
# 0.047 -> 0.045; worse: product_shot 0.106 -> 0.111. Their full frames 0.9-1.4 s -> 1.2-1.7 s on llvmpipe.
# Then a detached piece outside the box of its plane's largest piece kept as a cluster of its own where the clusters
# still fit (lpv/clusters.py _blocks: a strip of ground cut off by a façade had joined the ground beyond the
# building's corner): thin_walls 0.045 -> 0.043, outdoor 0.128 -> 0.125, product_shot 0.111 -> 0.109.
# 2026-12-07 (stop 54): the VCT rows re-measured after each voxel face got its own albedo (vct/inject.face_albedo:
# the mean over the surface points whose light leaves through it, a covered surface left out) in place of the voxel's
# mean albedo in the bounces, and the injection's light kept apart from it (the face's radiance = its albedo times
# its light's mean, where it was the mean of each point's product). Diffuse Indirect / Combined: rug_room 0.084 /
# 0.043 -> 0.062 / 0.032 (1.06 -> 1.02 of Cycles': the floor under the rug no longer tints the later bounces),
# furnished 0.086 / 0.050 -> 0.083 / 0.048; worse: thin_walls 0.043 / 0.050 -> 0.048 / 0.054 (0.98 -> 0.97 of
# Cycles'), many_lights 0.093 -> 0.095; the others within 0.001. Each bound is the lower of the old one and the
# rule's from this measurement (none of the old ones was exceeded).
# 2026-12-08 (stop 55): every row re-measured after the sky's cells that an opening's edge crosses were tested over
# their cones (direct/sky.glsl sky_soften: twelve taps of the direction's map over the cell's radius at the
# blockers' distance), the glossy share left unfiltered and the grazing cut-off lowered from cos 0.1 to 0.02.
# Diffuse Direct (both methods): window_room 0.059 -> 0.040, thin_walls 0.085 -> 0.052, outdoor 0.012 -> 0.010;
# Glossy Direct window_room 0.096 -> 0.074, thin_walls 0.199 -> 0.189; Combined outdoor LPV 0.034 -> 0.024. Worse:
# window_room's LPV Combined 0.070 -> 0.078 (its sky light was 2% dark and hid an indirect light 7% too bright:
# Diffuse Indirect 1.07 of Cycles', Glossy Indirect 1.14) and thin_walls' 0.034 -> 0.040 (the same: 1.04, 1.13);
# outdoor's Glossy Direct 0.040 -> 0.046. Each bound is the lower of the old one and the rule's (none exceeded).
# Then the slope-scaled part of the lights' shadow offset capped at tan θ = 1 (direct/eval.glsl MAX_SLOPE, was 8: up
# to 17 texels off the surface, which moved shadows' edges — a sofa lit by the sun through the wall 2 cm beside a
# window's edge): Diffuse Direct window_room 0.040 -> 0.033, metals 0.008 -> 0.006; Glossy Direct window_room 0.074
# -> 0.066, thin_walls 0.189 -> 0.186; nothing worse by 0.002. (Comparing each PCF tap with the receiver's plane
# instead, with no slope-scaled offset, measured lower still — window_room 0.031, furnished 0.011 — but lit the
# corners where a closed room's walls meet from a lamp outside: tests/stress/test_lights_camera.py.)
BOUNDS = {
    'default_principled': {
        'lpv': {'Combined': 0.037, 'Diffuse Direct': 0.008, 'Diffuse Indirect': 0.140, 'Diffuse Color': 0.003, 'Glossy Direct': 0.010, 'Glossy Indirect': 0.514, 'Glossy Color': 0.020, 'Diffuse Light': 0.038, 'Diffuse Color match': 0.998},
        'vct': {'Combined': 0.037, 'Diffuse Direct': 0.008, 'Diffuse Indirect': 0.114, 'Diffuse Color': 0.003, 'Glossy Direct': 0.010, 'Glossy Indirect': 0.384, 'Glossy Color': 0.020, 'Diffuse Light': 0.033, 'Diffuse Color match': 0.998},
    },
    'metals': {
        'lpv': {'Combined': 0.050, 'Diffuse Direct': 0.009, 'Diffuse Indirect': 0.150, 'Diffuse Color': 0.003, 'Glossy Direct': 0.031, 'Glossy Indirect': 0.589, 'Glossy Color': 0.013, 'Diffuse Light': 0.022, 'Diffuse Color match': 0.998},
        'vct': {'Combined': 0.044, 'Diffuse Direct': 0.009, 'Diffuse Indirect': 0.150, 'Diffuse Color': 0.003, 'Glossy Direct': 0.031, 'Glossy Indirect': 0.536, 'Glossy Color': 0.013, 'Diffuse Light': 0.024, 'Diffuse Color match': 0.998},
    },
    'textured': {
        'lpv': {'Combined': 0.013, 'Diffuse Direct': 0.002, 'Diffuse Indirect': 0.095, 'Diffuse Color': 0.002, 'Diffuse Light': 0.013, 'Diffuse Color match': 0.998},
        'vct': {'Combined': 0.020, 'Diffuse Direct': 0.002, 'Diffuse Indirect': 0.139, 'Diffuse Color': 0.002, 'Diffuse Light': 0.019, 'Diffuse Color match': 0.998},
    },
    'window_room': {
        'lpv': {'Combined': 0.080, 'Diffuse Direct': 0.040, 'Diffuse Indirect': 0.120, 'Diffuse Color': 0.003, 'Glossy Direct': 0.074, 'Glossy Indirect': 0.265, 'Glossy Color': 0.018, 'Diffuse Light': 0.075, 'Diffuse Color match': 0.998},
        'vct': {'Combined': 0.074, 'Diffuse Direct': 0.040, 'Diffuse Indirect': 0.097, 'Diffuse Color': 0.003, 'Glossy Direct': 0.074, 'Glossy Indirect': 0.198, 'Glossy Color': 0.018, 'Diffuse Light': 0.067, 'Diffuse Color match': 0.998},
    },
    'rug_room': {
        'lpv': {'Combined': 0.051, 'Diffuse Direct': 0.003, 'Diffuse Indirect': 0.098, 'Diffuse Color': 0.002, 'Glossy Direct': 0.016, 'Glossy Indirect': 0.240, 'Glossy Color': 0.020, 'Diffuse Light': 0.043, 'Diffuse Color match': 0.998},
        'vct': {'Combined': 0.061, 'Diffuse Direct': 0.003, 'Diffuse Indirect': 0.120, 'Diffuse Color': 0.002, 'Glossy Direct': 0.016, 'Glossy Indirect': 0.243, 'Glossy Color': 0.020, 'Diffuse Light': 0.053, 'Diffuse Color match': 0.998},
    },
    'thin_walls': {
        'lpv': {'Combined': 0.058, 'Diffuse Direct': 0.061, 'Diffuse Indirect': 0.078, 'Diffuse Color': 0.002, 'Glossy Direct': 0.223, 'Glossy Indirect': 0.343, 'Glossy Color': 0.025, 'Diffuse Light': 0.058, 'Diffuse Color match': 0.998},
        'vct': {'Combined': 0.064, 'Diffuse Direct': 0.061, 'Diffuse Indirect': 0.075, 'Diffuse Color': 0.002, 'Glossy Direct': 0.223, 'Glossy Indirect': 0.247, 'Glossy Color': 0.025, 'Diffuse Light': 0.065, 'Diffuse Color match': 0.998},
    },
    'lamp_room': {
        'lpv': {'Combined': 0.080, 'Diffuse Direct': 0.020, 'Diffuse Indirect': 0.150, 'Diffuse Color': 0.002, 'Glossy Direct': 0.033, 'Glossy Indirect': 0.449, 'Glossy Color': 0.017, 'Emission': 0.002, 'Diffuse Light': 0.117, 'Diffuse Color match': 0.998},
        'vct': {'Combined': 0.080, 'Diffuse Direct': 0.020, 'Diffuse Indirect': 0.150, 'Diffuse Color': 0.002, 'Glossy Direct': 0.033, 'Glossy Indirect': 0.383, 'Glossy Color': 0.017, 'Emission': 0.002, 'Diffuse Light': 0.135, 'Diffuse Color match': 0.998},
    },
    'many_lights': {
        'lpv': {'Combined': 0.059, 'Diffuse Direct': 0.011, 'Diffuse Indirect': 0.089, 'Diffuse Color': 0.004, 'Glossy Direct': 0.057, 'Glossy Indirect': 0.210, 'Glossy Color': 0.032, 'Diffuse Light': 0.061, 'Diffuse Color match': 0.998},
        'vct': {'Combined': 0.080, 'Diffuse Direct': 0.011, 'Diffuse Indirect': 0.135, 'Diffuse Color': 0.004, 'Glossy Direct': 0.057, 'Glossy Indirect': 0.224, 'Glossy Color': 0.032, 'Diffuse Light': 0.093, 'Diffuse Color match': 0.998},
    },
    'outdoor': {
        'lpv': {'Combined': 0.029, 'Diffuse Direct': 0.013, 'Diffuse Indirect': 0.150, 'Diffuse Color': 0.003, 'Glossy Direct': 0.048, 'Glossy Indirect': 0.612, 'Glossy Color': 0.033, 'Diffuse Light': 0.016, 'Diffuse Color match': 0.998},
        'vct': {'Combined': 0.034, 'Diffuse Direct': 0.013, 'Diffuse Indirect': 0.254, 'Diffuse Color': 0.003, 'Glossy Direct': 0.048, 'Glossy Indirect': 0.679, 'Glossy Color': 0.033, 'Diffuse Light': 0.019, 'Diffuse Color match': 0.998},
    },
    'product_shot': {
        'lpv': {'Combined': 0.041, 'Diffuse Direct': 0.020, 'Diffuse Indirect': 0.150, 'Diffuse Color': 0.003, 'Glossy Direct': 0.034, 'Glossy Indirect': 0.621, 'Glossy Color': 0.016, 'Diffuse Light': 0.035, 'Diffuse Color match': 0.996},
        'vct': {'Combined': 0.041, 'Diffuse Direct': 0.020, 'Diffuse Indirect': 0.150, 'Diffuse Color': 0.003, 'Glossy Direct': 0.034, 'Glossy Indirect': 0.483, 'Glossy Color': 0.016, 'Diffuse Light': 0.039, 'Diffuse Color match': 0.996},
    },
    'furnished': {
        'lpv': {'Combined': 0.078, 'Diffuse Direct': 0.020, 'Diffuse Indirect': 0.149, 'Diffuse Color': 0.003, 'Glossy Direct': 0.032, 'Glossy Indirect': 0.250, 'Glossy Color': 0.025, 'Emission': 0.009, 'Diffuse Light': 0.083, 'Diffuse Color match': 0.998},
        'vct': {'Combined': 0.073, 'Diffuse Direct': 0.020, 'Diffuse Indirect': 0.133, 'Diffuse Color': 0.003, 'Glossy Direct': 0.032, 'Glossy Indirect': 0.232, 'Glossy Color': 0.025, 'Emission': 0.009, 'Diffuse Light': 0.075, 'Diffuse Color match': 0.998},
    },
    'cornell_animated': {
        'lpv': {'Combined': 0.045, 'Diffuse Direct': 0.010, 'Diffuse Indirect': 0.092, 'Diffuse Color': 0.002, 'Diffuse Light': 0.044, 'Diffuse Color match': 0.999},
        'vct': {'Combined': 0.059, 'Diffuse Direct': 0.010, 'Diffuse Indirect': 0.131, 'Diffuse Color': 0.002, 'Diffuse Light': 0.061, 'Diffuse Color match': 0.999},
    },
}

METHODS = ("lpv", "vct")
# Both methods on all twelve scenes: 60 s here (llvmpipe, 2 cores; 2026-12-07, stop 53). VCT's four slowest scenes
# were marked slow while the run took 6 min 56 s; since VCT's trace, replays and emitters got faster every pair runs
# in the default run (CI).


@pytest.fixture(scope="module")
def measured(request, tmp_path_factory):
    """{scene: row} of tests/support/examples_table.py --json for the scene × method pairs this session's selected
    tests use: one subprocess per method (bpy's global state stays out of pytest)."""
    wanted = {}
    for item in request.session.items:
        params = getattr(getattr(item, "callspec", None), "params", {})
        if item.module is request.module and "name" in params:
            wanted.setdefault(params["method"], set()).add(params["name"])
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path_factory.mktemp("blender_user")))
    rows = {}
    for method, names in sorted(wanted.items()):
        proc = subprocess.run([sys.executable, str(ROOT / "tests/support/examples_table.py"), "--json", *sorted(names),
                               "--methods", method], capture_output=True, text=True, env=env, timeout=1800)
        line = next((l for l in proc.stdout.splitlines() if l.startswith("RESULT ")), None)
        assert proc.returncode == 0 and line, f"examples_table failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
        for name, row in json.loads(line[len("RESULT "):]).items():
            rows.setdefault(name, {}).update(row)
    return rows


def test_every_reference_has_bounds():
    assert set(BOUNDS) == set(references.FRAMES), "BOUNDS and examples/references disagree: re-run examples_table.py"
    for name, methods in BOUNDS.items():
        assert set(methods) == set(METHODS), name


def test_references_are_the_projects_cycles_settings():
    """The committed data is what the issue asks for: the project's reference settings (addon/reference/cycles.py),
    ≥ 1024 spp (the transport tests' ≥ 4096) × seeds 1 and 2, 160×120, 8 bounces (and 1 for the transport tests'
    one-bounce references), every compared pass, small."""
    total = 0
    for name in references.names():
        ref = references.load(name)
        m = ref.meta
        scene, frame, bounces = references.spec(name)
        assert m["scene"] == scene and m["frame"] == frame and m["bounces"] == bounces, name
        assert m["samples"] >= references.default_samples(name) and m["seeds"] == [1, 2]
        assert m["resolution"] == [160, 120]
        assert m["cycles"]["filter_width_px"] == 0.01 and not m["cycles"]["adaptive_sampling"]
        assert set(references.PASSES) | {"Depth"} == set(ref.passes)
        assert all(ref.passes[p].shape == (120, 160, 3) for p in references.PASSES)
        assert ref.hit.mean() > 0.3, name  # the camera sees the scene
        total += sum(os.path.getsize(p) for p in references.paths(name))
    assert total < 8 * 2 ** 20


def _cases():
    return [pytest.param(name, method, id=f"{name}-{method}") for name in references.FRAMES for method in METHODS]


@pytest.mark.parametrize("name,method", _cases())
def test_example_against_cycles(measured, name, method):
    row = measured[name]
    assert not row["stale"], row["stale"]
    got = row[method]
    print(name, method, {k: v for k, v in got["rel_l1"].items()}, MATCH, got[MATCH], "noise floor",
          row["noise_floor"])
    failures = []
    for key, bound in BOUNDS[name][method].items():
        if key == MATCH:
            if not got[MATCH] >= bound:
                failures.append(f"{MATCH} {got[MATCH]:.4f} < {bound} (seed-unstable {row['diffuse_color_unstable']})")
            continue
        value = got["rel_l1"].get(key)
        if value is None or not value <= bound:
            target = f", target {TARGETS[key]}" if key in TARGETS else ""
            failures.append(f"{key} {value} > {bound} (noise floor {row['noise_floor'].get(key)}{target})")
    assert not failures, f"{name} {method}: " + "; ".join(failures)

