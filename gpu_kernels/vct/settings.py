# SPDX-License-Identifier: GPL-3.0-or-later
"""VctSettings: every knob of the voxel cone tracer, validated, and the subsets each pass's cache key reads."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from .cones import MAX_CONES, valid_cone_count

MAX_SUBRAYS = 7  # vct/crossing.glsl keeps them in registers (a define per count)
CONE_FIELDS = ("diffuse_cones", "diffuse_aperture", "max_distance", "step_multiplier", "start_offset")
# The narrowest diffuse cone (degrees). A cone steps one texel of its own level at a time (vct/crossing.glsl), so a
# narrow one takes many steps, each a few loop iterations, and llvmpipe ends a shader invocation's loops silently
# after 65535 iterations in all (lpv/gather.vpls_per_dispatch): 31 cones of 5° at 512³ take about 1 500 steps
# (49 a cone), 1° about 5 300.
MIN_APERTURE = 5.0


@dataclass(frozen=True)
class VctSettings:
    resolution: int = 64  # voxels along the longest axis of the scene (other axes padded, see vct_grid)
    # A cap around the normal and one ring (5..9) or two rings (13, 16, … 31), cone_table, each cone a bundle of
    # `subrays` rays (anisotropic volumes, vct/crossing.glsl). Default 16 × 5, measured 2026-12-06 (64³, defaults
    # otherwise, 160×120, against 8-bounce Cycles; Diffuse Indirect / Combined rel-L1; the per-pixel trace on
    # llvmpipe, Cornell): 9 × 7 (the default before): Cornell 0.101 / 0.051, spot room 0.052 / 0.019, courtyard
    # 0.091 / 0.066, 0.68 s; 16 × 4: 0.098 / 0.049, 0.056 / 0.021, 0.089 / 0.065, 0.90 s; 16 × 5: 0.091 / 0.046,
    # 0.050 / 0.019, 0.089 / 0.065, 1.05 s. On the scenes like users' (tests/support/examples_table.py) 9 × 7 missed
    # two targets that 16 × 5 meets: many_lights' Combined 0.094 → 0.066 (a long hall: one ring of wide cones
    # under-read the light its walls and floor bounce, 0.86 → 0.92 of Cycles'), metals' Diffuse Indirect 0.179 →
    # 0.142; the others within 0.005 or closer to Cycles but lamp_room (Combined 0.047 → 0.052). Against an exact
    # view factor (tests/gpu/test_vct.py, a lit patch seen from a plate and a wall) 16 × 5 reads 1.07× where 9 × 7
    # read 0.96–1.01 and 19 × 4 (as fast as 16 × 5) 1.03–1.05, which met the same two targets with the scenes a
    # little further from Cycles (outdoor 0.239 against 0.219). 19 × 7: Cornell 0.074 / 0.043 in an earlier measure,
    # at twice the trace of 9 × 7.
    diffuse_cones: int = 16
    # Rays per diffuse cone in the per-pixel trace with anisotropic volumes (vct/crossing.glsl): the axis and
    # subrays − 1 around it; each meets surfaces where it crosses them. 1 = the axis only (9 cones: 0.202 / 0.102,
    # 0.099 / 0.036, 0.234 / 0.163). The trace's cost grows about linearly with it.
    subrays: int = 5
    # Cones per voxel face in the bounce gathers (vct/bounce.py); 0 = diffuse_cones. Bounced light is smooth, and
    # these gathers are most of a multi-bounce frame's time. Default 6, measured against 9 (64³, defaults otherwise,
    # Combined rel-L1 / bounce pass on llvmpipe): Cornell 0.092 vs 0.093 / 3.6 s vs 4.9 s, spot room 0.053 vs
    # 0.058, courtyard 0.180 vs 0.181; 5 cones: 0.095 / 3.2 s, 0.058, 0.169.
    bounce_cones: int = 6
    diffuse_aperture: float = 0.0  # cone half-angle (degrees); 0 = derived: a cone of the region's solid angle
    max_distance: float = 0.0  # metres a cone travels; 0 = until it leaves the grid (or is fully occluded)
    # Indirect bounces in Diffuse Indirect (1 = light reflected once; Cycles' "1 bounce"). Default 8 like Cycles'
    # default: with 1 bounce the interiors came out 0.48 (Cornell) / 0.73 (spot room) Diffuse Indirect rel-L1,
    # most of it light missing.
    bounces: int = 8
    # Gather only this many bounces and extrapolate the rest up to `bounces` as a geometric series of the last
    # increment (vct/bounce.extrapolate_tail); 0 = gather every bounce. Each gathered bounce is a full cone pass
    # over the voxels, the tail a few array operations. Default 4, measured against gathering all 8 (Combined
    # rel-L1, 64³, 9 cones everywhere): Cornell 0.093 vs 0.092, spot room 0.058 vs 0.056, courtyard 0.181 vs 0.180
    # in half the time (Cornell bounce pass 4.8 s vs 11.0 s on llvmpipe); gathering 3 was 0.098 / 0.057 / 0.198.
    gathered_bounces: int = 4
    # Stop gathering once a bounce adds less than this fraction of the first bounce's flux (and extrapolate nothing
    # after it): a dark scene's series ends early, reported in "skipped_work" (vct/bounce.py).
    epsilon: float = 1e-3
    # Step / sampled voxel size of the volumetric march (Freed 2018, listing 4.1, steps by the cone radius): the bounce
    # gathers, the specular cone, isotropic volumes. The per-pixel sub-rays step one texel (vct/crossing.glsl).
    step_multiplier: float = 0.5
    start_offset: float = 1.5  # voxels along the normal (× ‖n‖₁): the trilinear support of the own texel
    # One glossy cone per pixel along the reflected view direction → Glossy Indirect (vct/specular.py); pixels
    # with no glossy closure or rougher than roughness_cutoff run no cone, so scenes without glossy materials pay
    # one texture fetch per pixel.
    specular_cone: bool = True
    roughness_cutoff: float = 0.5  # specular cone skipped above this Principled roughness (Glossy Indirect = 0)
    # Diffuse cones traced at (width/s) × (height/s) and brought back to full resolution by a depth- and
    # normal-aware upsampling (Kircher and Lawrance 2009, inferred lighting; vct/upsample.py). 1 = every pixel.
    # Default 2: bounced light is smooth, and pixels no low-resolution sample matches are traced again. Measured on
    # the twelve example scenes (benchmarks/results/vct_llvmpipe.md): Diffuse Indirect against Cycles within ±0.004
    # of every pixel's trace, the frame 25–45% faster on llvmpipe.
    indirect_scale: int = 2
    # Temporal accumulation (vct/temporal.py): each render turns the diffuse cone set about the normal by another
    # angle and averages into a history, until this many frames are in; any change to the trace's inputs restarts
    # it. 0 or 1 = off.
    temporal_frames: int = 0
    # After a camera move, a sample takes the last view's gather where that was traced on its surface within this
    # many of its texels (vct/reuse.py); the others are traced. 0 = trace every sample again. Default half a texel's
    # diagonal, the farthest any point lies from the nearest texel centre: a surface seen again finds a last sample
    # almost everywhere. Measured (benchmarks/results/vct_llvmpipe.md): 0.5 retraced 2-3 times as many samples
    # for the same error against Cycles.
    reuse_reach: float = 0.71
    cone_rotation: float = 0.0  # degrees the diffuse cone set is turned about the normal (the jitter adds to it)
    # Six directional volumes (Crassin) rather than one isotropic volume. Default on, measured: isotropic voxels
    # show a wall's lit side from both sides, and with 4 bounces Cornell / courtyard Diffuse Indirect came out
    # 1.8× / 5.1× as bright as 8-bounce Cycles (anisotropic: 0.96× / 0.98×).
    anisotropic: bool = True
    ao_distance: float = 0.0  # metres for voxel AO; 0 = AO is the sky visibility (cones leaving the grid)

    def __post_init__(self):
        checks = [
            (16 <= self.resolution <= 512, f"resolution {self.resolution} out of range 16..512"),
            (valid_cone_count(self.diffuse_cones), f"diffuse_cones {self.diffuse_cones} must be 5..9 or 13, 16, "
             f"19, … {MAX_CONES - 1}"),
            (isinstance(self.subrays, int) and 1 <= self.subrays <= MAX_SUBRAYS,
             f"subrays {self.subrays} out of range 1..{MAX_SUBRAYS}"),
            (self.bounce_cones == 0 or valid_cone_count(self.bounce_cones),
             f"bounce_cones {self.bounce_cones} must be 0 (= diffuse_cones), 5..9 or 13, 16, 19, … {MAX_CONES - 1}"),
            (self.diffuse_aperture == 0 or MIN_APERTURE <= self.diffuse_aperture < 90,
             f"diffuse_aperture {self.diffuse_aperture} must be 0 (derived) or in [{MIN_APERTURE:g}, 90) degrees"),
            (self.max_distance >= 0 and math.isfinite(self.max_distance), "max_distance must be ≥ 0 (0 = unlimited)"),
            (1 <= self.bounces <= 16, f"bounces {self.bounces} out of range 1..16"),
            (0.0 <= self.epsilon < 1.0, f"epsilon {self.epsilon} out of range [0, 1)"),
            (self.gathered_bounces == 0 or 2 <= self.gathered_bounces <= 16,
             f"gathered_bounces {self.gathered_bounces} must be 0 (gather all) or 2..16 (the tail needs a ratio)"),
            (0.05 <= self.step_multiplier <= 2.0, f"step_multiplier {self.step_multiplier} out of range 0.05..2"),
            (0.0 <= self.start_offset <= 8.0, f"start_offset {self.start_offset} out of range 0..8 voxels"),
            (0.0 <= self.roughness_cutoff <= 1.0, f"roughness_cutoff {self.roughness_cutoff} out of range 0..1"),
            (self.ao_distance >= 0 and math.isfinite(self.ao_distance), "ao_distance must be ≥ 0"),
            (self.indirect_scale in (1, 2, 4), f"indirect_scale {self.indirect_scale} must be 1, 2 or 4"),
            (0 <= self.temporal_frames <= 256, f"temporal_frames {self.temporal_frames} out of range 0..256"),
            (0.0 <= self.reuse_reach <= 1.0, f"reuse_reach {self.reuse_reach} out of range 0..1 texels"),
            (math.isfinite(self.cone_rotation), "cone_rotation must be finite"),
        ]
        for ok, message in checks:
            if not ok:
                raise ValueError(message)

    def key(self, kind: str) -> tuple:
        """The settings a pass reads: 'bounce', 'trace' (diffuse cones per pixel, upsampling, accumulation) or
        'specular' (resolution and anisotropy key the earlier passes)."""
        extra = {"bounce": CONE_FIELDS + ("bounce_cones", "bounces", "gathered_bounces", "epsilon"),
                 "trace": CONE_FIELDS + ("subrays", "ao_distance", "indirect_scale", "cone_rotation",
                                         "temporal_frames", "reuse_reach"),
                 "specular": ("max_distance", "step_multiplier", "start_offset", "specular_cone",
                              "roughness_cutoff")}[kind]
        d = asdict(self)
        if kind == "bounce" and self.bounce_cones:  # the gathers at voxel faces use bounce_cones, not diffuse_cones
            extra = tuple(name for name in extra if name != "diffuse_cones")
        return tuple((name, d[name]) for name in extra)


def traced_texels(width: int, height: int, settings: VctSettings) -> tuple:
    """(w, h) texels the per-pixel trace runs at for a width × height image: ceil(W/s) × ceil(H/s) for
    s = indirect_scale."""
    scale = int(settings.indirect_scale)
    return -(-int(width) // scale), -(-int(height) // scale)
