# SPDX-License-Identifier: GPL-3.0-or-later
"""Method settings from the command line (`--lpv key=value ...`, `--vct ...`), automatic quality
(`--budget-ms`, `--target-error`), and the one render call `render` and `compare` share."""
from __future__ import annotations

import dataclasses

from ..scene_io import CliError


def parse_method_options(pairs, settings_cls=None, flag: str = "--lpv") -> dict:
    """`--lpv key=value ...` (or `--vct ...`) → keyword arguments of the method's settings dataclass, typed like
    its fields."""
    if settings_cls is None:
        from ...gpu_kernels.lpv.settings import LpvSettings as settings_cls

    fields = {f.name: f for f in dataclasses.fields(settings_cls)}
    out = {}
    for pair in pairs or ():
        key, sep, value = pair.partition("=")
        if not sep or key not in fields:
            raise CliError(f"{flag} {pair}: expected KEY=VALUE with KEY one of {', '.join(fields)}")
        default = getattr(settings_cls(), key)
        try:
            if isinstance(default, bool):
                if value.lower() not in ("1", "0", "true", "false", "yes", "no", "on", "off"):
                    raise ValueError(value)
                out[key] = value.lower() in ("1", "true", "yes", "on")
            else:
                out[key] = type(default)(value)
        except (TypeError, ValueError):
            raise CliError(f"{flag} {pair}: {value!r} is not a valid {type(default).__name__}") from None
    return out


def vct_options(pairs) -> dict:
    from ...gpu_kernels.vct.settings import VctSettings

    return parse_method_options(pairs, VctSettings, "--vct")


def method_settings(scene, method: str, lpv_pairs=None, vct_pairs=None):
    """RenderSettings at the scene's resolution from --method and the --lpv / --vct KEY=VALUE pairs."""
    return settings_of(scene, method, parse_method_options(lpv_pairs), vct_options(vct_pairs))


def settings_of(scene, method: str, lpv_options: dict | None, vct_settings: dict | None):
    from ...gpu_kernels.lpv.settings import LpvSettings
    from ...gpu_kernels.settings import RenderSettings
    from ...gpu_kernels.vct.settings import VctSettings

    try:
        lpv_settings = LpvSettings(**(lpv_options or {}))
        vct = VctSettings(**(vct_settings or {}))
    except ValueError as exc:
        raise CliError(f"method settings: {exc}") from None
    return RenderSettings(method=method, width=scene.resolution[0], height=scene.resolution[1],
                          lpv=lpv_settings, vct=vct)


def render_ours(scene, method: str, lpv_options: dict | None = None, vct_settings: dict | None = None):
    from ...gpu_kernels.engine import get_engine

    settings = settings_of(scene, method, lpv_options, vct_settings)
    return engine_result(lambda: get_engine().render(scene, settings))


def engine_result(call):
    """`call()`, with the engine's errors meant for the user (bad input, no OpenGL 4.3, the GPU failing, a grid
    too large) as one-line CliErrors."""
    from ...gpu_kernels.gl.context import GpuUnavailableError
    from ...gpu_kernels.settings import SceneError

    try:
        return call()
    except (SceneError, NotImplementedError, GpuUnavailableError) as exc:
        raise CliError(" ".join(str(exc).split())) from None


def auto_quality(args) -> dict | None:
    """--budget-ms / --target-error: choose method and settings from the measured table (addon/quality.py);
    fills args.method, args.lpv, args.vct and returns what to report, or None when neither was given."""
    if args.budget_ms is None and args.target_error is None:
        return None
    from ..quality import QualityError, choose, load_table

    if args.lpv or args.vct:
        raise CliError("--budget-ms/--target-error choose the method's settings; leave out --lpv/--vct")
    try:
        table = load_table()
        choice = choose(table, args.budget_ms, args.target_error, args.method)
    except QualityError as exc:
        raise CliError(str(exc)) from None
    args.method = choice.method
    from ...gpu_kernels.lpv.settings import LpvSettings
    from ...gpu_kernels.vct.settings import VctSettings

    cls = {"lpv": LpvSettings, "vct": VctSettings}.get(choice.method)
    known = {f.name for f in dataclasses.fields(cls)} if cls else set()
    pairs = [f"{k}={v}" for k, v in choice.settings.items() if k in known]  # a newer/older table's extra keys
    args.lpv, args.vct = (pairs, None) if choice.method == "lpv" else (None, pairs) if choice.method == "vct" \
        else (None, None)
    return {"method": choice.method, "settings": choice.settings, "measured_seconds": choice.seconds,
            "measured_rel_l1": choice.rel_l1, "message": choice.describe(table)}
