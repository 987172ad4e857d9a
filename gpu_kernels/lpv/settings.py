# SPDX-License-Identifier: GPL-3.0-or-later
"""LpvSettings: every knob of the Light Propagation Volumes, validated."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class LpvSettings:
    resolution: int = 32  # cells along the longest axis of the (finest) grid
    cascades: int = 1  # nested grids, each twice the extent of the last
    rsm_resolution: int = 128  # texels per side of each RSM view (sun: twice that, at most 4 texels per LPV cell)
    rsm_downsample: int = 1  # propagate: inject one VPL per k×k RSM texels, intensity-aware (Kaplanyan 2009); 1, 2, 4
    max_iterations: int = 64
    epsilon: float = 1e-3  # stop when one step moved less than this fraction of the injected flux
    occlusion: bool = True  # fuzzy occlusion from the geometry volume
    clamp_negative: bool = False
    damping: bool = False  # Elvek 2012's directional-derivative damping at lookup
    blend_cells: float = 2.0  # cascade border blend width (cells)
    bounces: int = 8  # indirect bounces (1 = light reflected once; Cycles' default 8); > 1 need occlusion
    # Gathered transport: gather this many bounces, extrapolate the rest to `bounces` as a geometric series of the
    # last pass (lpv/tail.glsl); 0 = gather every bounce. The propagating transport propagates every bounce.
    gathered_bounces: int = 4
    lookup: str = "flux"  # "flux": absorbed face flux per area (conserves energy); "intensity": Kaplanyan's I/cell²
    # Octree LPV (Olovsson and Doggett 2013, lpv/octree.py): 0 = uniform grid; L ≥ 1 = full octree O_0..O_{L-1}
    # (O_0 = this grid, O_i = n/2^i), index volume, per-level propagation, merge (L = 1: the octree path with one
    # level, which equals the uniform grid with `octree_iterations` steps, one bounce, intensity lookup).
    octree_levels: int = 0
    octree_iterations: int = 4  # propagation steps on every octree level (Olovsson and Doggett 2013, §4: k = 4)
    # Transport: "gather" sends light straight from VPLs to every surface voxel with fuzzy visibility, bounce by
    # bounce (lpv/gather.py: the face scheme turns light sideways within a few cells); "propagate" is the classic
    # LPV. World light bounces either way (the sky light's RSMs). The gather writes surface voxels' irradiance, which only the flux
    # lookup with occlusion reads: the intensity lookup, occlusion=False and the octree always propagate (see
    # `gathers`). `gather_vpls` bounds the VPLs per bounce: RSM texels and surface voxels are clustered to fit.
    # "transfer" is the gather with its sources fixed per geometry and the kernel cached (lpv/transfer.py): an
    # edit of lights, materials or world re-runs no visibility; `transfer_mb` bounds the cache (MiB per cascade),
    # past which it gathers. Its clusters: `gather_vpls`, or up to twice as many where clusters × surface voxels
    # stay within `transfer_pairs` (the kernel evaluations of a full build: a scene of few surface voxels — an
    # outdoor block at 32³, a few objects on a floor — gets finer clusters for the time a large room's take).
    transport: str = "transfer"
    gather_vpls: int = 512
    transfer_mb: int = 512
    transfer_pairs: int = 12_000_000

    def __post_init__(self):
        if not 4 <= self.resolution <= 256:
            raise ValueError(f"resolution {self.resolution} out of range 4..256")
        if not 1 <= self.cascades <= 4:
            raise ValueError(f"cascades {self.cascades} out of range 1..4")
        if self.lookup not in ("flux", "intensity"):
            raise ValueError(f"lookup must be 'flux' or 'intensity', not {self.lookup!r}")
        if self.transport not in ("transfer", "gather", "propagate"):
            raise ValueError(f"transport must be 'transfer', 'gather' or 'propagate', not {self.transport!r}")
        if self.transfer_mb < 1 or self.transfer_pairs < 0:
            raise ValueError(f"transfer_mb {self.transfer_mb} must be ≥ 1 and transfer_pairs {self.transfer_pairs} ≥ 0")
        if self.gathered_bounces < 0:
            raise ValueError(f"gathered_bounces {self.gathered_bounces} must be ≥ 0 (0: gather every bounce)")
        if not 16 <= self.gather_vpls <= 65536:
            raise ValueError(f"gather_vpls {self.gather_vpls} out of range 16..65536")
        if self.rsm_downsample not in (1, 2, 4):
            raise ValueError(f"rsm_downsample must be 1, 2 or 4, not {self.rsm_downsample}")
        if self.bounces < 1 or self.max_iterations < 1 or self.rsm_resolution < 8:
            raise ValueError("bounces and max_iterations must be ≥ 1 and rsm_resolution ≥ 8")
        if not 0 <= self.octree_levels <= 5 or self.octree_iterations < 1:
            raise ValueError("octree_levels must be 0..5 and octree_iterations ≥ 1")
        if self.octree_levels and (self.cascades != 1 or not self.occlusion
                                   or 2 ** (self.octree_levels - 1) > self.resolution):
            raise ValueError("the octree LPV needs cascades=1, occlusion (its index volume comes from the geometry "
                             "volume) and 2^(octree_levels-1) ≤ resolution")

    @property
    def gathers(self) -> bool:
        """Whether light is gathered (transport "gather" or "transfer" where the flux lookup reads it)."""
        return (self.transport in ("gather", "transfer") and self.lookup == "flux" and self.occlusion
                and not self.octree_levels)
