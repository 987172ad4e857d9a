# SPDX-License-Identifier: GPL-3.0-or-later
"""Automatic quality: pick method and settings for a time budget and/or an error target from the measured table
`quality_front.json` that `bounce-gi bench` writes (committed next to this file; regenerate with `make bench`).

The table holds, per setting of our sweep, the median frame time and the mean Combined rel-L1 against Cycles over
the benched example scenes, on the machine named in it. Times are for that machine and resolution: on another GPU
they scale, but the order of the settings on the front is what the choice relies on.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass

TABLE_PATH = os.path.join(os.path.dirname(__file__), "quality_front.json")


class QualityError(ValueError):
    """No table, or an impossible request; the message is for the user."""


@dataclass
class Choice:
    method: str
    settings: dict  # the method's settings (LpvSettings / VctSettings fields; {} for "none")
    seconds: float  # measured frame time on the table's machine
    rel_l1: float  # measured mean Combined rel-L1
    label: str
    reason: str  # one line saying why this one was chosen

    def describe(self, table: dict) -> str:
        machine = table.get("machine", {}).get("gl_renderer", "an unknown GPU")
        res = table.get("resolutions") or [[0, 0]]
        return (f"chose {self.label}: {self.reason} (measured {self.seconds * 1000:.0f} ms per frame and "
                f"Combined rel-L1 {self.rel_l1:.3f} vs Cycles, mean over {', '.join(table.get('scenes', []))} at "
                f"{res[0][0]}x{res[0][1]} on {machine})")


_loaded: dict = {}  # path -> (modification time, table): the viewport asks on every depsgraph update


def load_table(path: str = TABLE_PATH) -> dict:
    try:
        stamp = os.stat(path).st_mtime_ns
        if path in _loaded and _loaded[path][0] == stamp:
            return _loaded[path][1]
        with open(path) as f:
            table = json.load(f)
        entries = table["entries"]
        if not entries or not all({"method", "settings", "seconds", "rel_l1"} <= set(e) for e in entries):
            raise ValueError("entries lack method/settings/seconds/rel_l1")
        _loaded[path] = (stamp, table)
        return table
    except FileNotFoundError:
        raise QualityError(f"no quality table at {path}; run `make bench` to measure one") from None
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise QualityError(f"quality table {path} is unreadable ({exc}); run `make bench` again") from None


def choose(table: dict, budget_ms: float | None = None, target_error: float | None = None,
           method: str | None = None) -> Choice:
    """The most accurate setting within the budget; the fastest that reaches the target error; with both, the
    fastest reaching the target within the budget, else the most accurate within the budget. `method` restricts the
    choice to one method. When nothing fits, the closest setting is chosen and the reason says so."""
    if budget_ms is not None and not (budget_ms > 0 and math.isfinite(budget_ms)):
        raise QualityError(f"time budget {budget_ms} ms must be a positive number")
    if target_error is not None and not (target_error > 0 and math.isfinite(target_error)):
        raise QualityError(f"target error {target_error} must be a positive number (a rel-L1, e.g. 0.2)")
    if budget_ms is None and target_error is None:
        raise QualityError("give a time budget, a target error, or both")
    entries = [e for e in table["entries"] if method is None or e["method"] == method]
    if not entries:
        raise QualityError(f"the quality table has no measured settings for method '{method}'")
    fastest = min(entries, key=lambda e: e["seconds"])
    most_accurate = min(entries, key=lambda e: e["rel_l1"])
    within = [e for e in entries if budget_ms is None or e["seconds"] * 1000 <= budget_ms]
    reaching = [e for e in within if target_error is None or e["rel_l1"] <= target_error]
    if reaching and target_error is not None:
        pick = min(reaching, key=lambda e: e["seconds"])
        reason = f"the fastest measured to reach rel-L1 ≤ {target_error:g}" + \
            (f" within {budget_ms:g} ms" if budget_ms is not None else "")
    elif within and budget_ms is not None:
        pick = min(within, key=lambda e: e["rel_l1"])
        reason = f"the most accurate within {budget_ms:g} ms" + \
            (f"; none reaches rel-L1 ≤ {target_error:g} in that time" if target_error is not None else "")
    elif budget_ms is not None:  # nothing within the budget
        pick = fastest
        reason = f"nothing measured fits {budget_ms:g} ms, so the fastest"
    else:
        pick = most_accurate
        reason = f"nothing measured reaches rel-L1 ≤ {target_error:g}, so the most accurate"
    return Choice(pick["method"], dict(pick["settings"]), pick["seconds"], pick["rel_l1"],
                  pick.get("label", pick["method"]), reason)


def render_settings_for(choice: Choice, width: int, height: int):
    """The RenderSettings a Choice stands for (unknown keys from an older table are ignored; an LPV row of the
    per-bounce gather runs as the cached transfer)."""
    import dataclasses

    from ..gpu_kernels.lpv.settings import LpvSettings
    from ..gpu_kernels.settings import RenderSettings
    from ..gpu_kernels.vct.settings import VctSettings

    def build(cls):
        names = {f.name for f in dataclasses.fields(cls)}
        values = {k: v for k, v in choice.settings.items() if k in names}
        if cls is LpvSettings and values.get("transport") == "gather":
            # Rows measured before the cached transport existed: it evaluates the same kernel (lpv/transfer.py)
            # and re-uses it across edits, which is what a preview that follows edits needs; `make bench`
            # measures it directly.
            values["transport"] = "transfer"
        return cls(**values)

    kwargs = {"lpv": build(LpvSettings)} if choice.method == "lpv" else \
        {"vct": build(VctSettings)} if choice.method == "vct" else {}
    return RenderSettings(method=choice.method, width=width, height=height, **kwargs)


# Quality presets. With method Auto, a preset is an error target for choose(): the fastest measured setting that
# reaches it (the table's front on the dev box: LPV 16³ reaches 0.07, LPV 32³ 0.056, LPV 32³ with 1024 VPLs 0.05).
# With a method chosen by hand, a preset is that method's settings: Medium is its defaults.
QUALITIES = ("DRAFT", "MEDIUM", "HIGH")
AUTO_TARGETS = {"DRAFT": 0.07, "MEDIUM": 0.056, "HIGH": 0.05}
PRESETS = {
    "lpv": {"DRAFT": {"resolution": 16}, "MEDIUM": {}, "HIGH": {"gather_vpls": 1024}},
    "vct": {"DRAFT": {"resolution": 32, "diffuse_cones": 6, "subrays": 1}, "MEDIUM": {},
            "HIGH": {"diffuse_cones": 19}},
}


def preset_settings(method: str, quality: str, width: int, height: int, bounces: int = 0, resolution: int = 0):
    """RenderSettings for a method chosen by hand at a quality preset; `bounces` and `resolution` (grid cells along
    the longest axis), when not 0, override the preset's (the panel's advanced settings)."""
    import dataclasses

    from ..gpu_kernels.lpv.settings import LpvSettings
    from ..gpu_kernels.settings import RenderSettings
    from ..gpu_kernels.vct.settings import VctSettings

    if quality not in QUALITIES:
        raise QualityError(f"unknown quality {quality!r} (choose from {', '.join(QUALITIES)})")
    if method not in PRESETS:
        return RenderSettings(method=method, width=width, height=height)
    values = dict(PRESETS[method][quality])
    values.update({k: v for k, v in (("bounces", bounces), ("resolution", resolution)) if v})
    cls = LpvSettings if method == "lpv" else VctSettings
    try:
        settings = dataclasses.replace(cls(), **values)
    except ValueError as ex:
        raise QualityError(f"{method.upper()} settings: {ex}") from None
    return RenderSettings(method=method, width=width, height=height, **{method: settings})
