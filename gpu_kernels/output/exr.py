# SPDX-License-Identifier: GPL-3.0-or-later
"""Multi-part EXR in Blender 5's layout (one part per pass, channels `ViewLayer.<Pass>.<C>`), and PNG previews.

Reading uses `read_image(subimage, miplevel, chbegin, chend, FLOAT)`: the 3-argument form silently returns the
first part (docs/conventions.md). Writing goes to a temporary file renamed into place, so a failed write never leaves a
half-written file.
"""
from __future__ import annotations

import os
import tempfile

import numpy as np

LAYER = "ViewLayer"
CHANNELS = {"Combined": "RGBA", "Depth": "Z", "Position": "XYZ", "Normal": "XYZ"}


def _channels(name: str, count: int) -> list[str]:
    letters = CHANNELS.get(name, "RGBA" if count == 4 else "RGB")
    return [f"{LAYER}.{name}.{c}" for c in letters[:count]]


def write_passes(path: str, passes: dict) -> None:
    """Write {pass name: (H, W, C) float32, rows top-to-bottom} as a multi-part float EXR."""
    import OpenImageIO as oiio

    specs, arrays = [], []
    for name, image in passes.items():
        image = np.ascontiguousarray(image, np.float32)
        if image.ndim == 2:
            image = image[..., None]
        h, w, c = image.shape
        spec = oiio.ImageSpec(w, h, c, oiio.FLOAT)
        spec.channelnames = tuple(_channels(name, c))
        spec.attribute("name", f"{LAYER}.{name}")
        spec.attribute("compression", "zip")
        specs.append(spec)
        arrays.append(image)
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(suffix=".exr", prefix=".bounce-gi-", dir=directory)
    os.close(fd)
    try:
        out = oiio.ImageOutput.create(tmp)
        if out is None or not out.open(tmp, specs):
            raise OSError(f"cannot write {path}: {oiio.geterror() or (out.geterror() if out else '')}")
        for i, (spec, image) in enumerate(zip(specs, arrays)):
            if i > 0 and not out.open(tmp, spec, "AppendSubimage"):
                raise OSError(f"cannot write {path}: {out.geterror()}")
            if not out.write_image(image):
                raise OSError(f"cannot write {path}: {out.geterror()}")
        out.close()
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def read_passes(path: str) -> dict:
    """Read every part of a (Blender or Bounce GI) multi-part EXR into {pass name: (H, W, C) float32}."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise OSError(f"cannot read {path}: {oiio.geterror()}")
    passes = {}
    try:
        sub = 0
        while inp.seek_subimage(sub, 0):
            spec = inp.spec()
            data = inp.read_image(sub, 0, 0, spec.nchannels, oiio.FLOAT)
            data = np.asarray(data, np.float32).reshape(spec.height, spec.width, spec.nchannels)
            # Group channels by pass: "ViewLayer.Diffuse Direct.R" -> "Diffuse Direct"
            groups: dict = {}
            for i, ch in enumerate(spec.channelnames):
                parts = ch.split(".")
                name = parts[-2] if len(parts) >= 2 else ch
                groups.setdefault(name, []).append(i)
            for name, idx in groups.items():
                passes[name] = np.ascontiguousarray(data[..., idx])
            sub += 1
    finally:
        inp.close()
    return passes


def tonemap_srgb(image: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """Scene-linear RGB → 8-bit sRGB for PNG previews only (never applied to data)."""
    x = np.clip(np.asarray(image[..., :3], np.float64) * 2.0 ** exposure, 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (srgb * 255 + 0.5).astype(np.uint8)


def write_png(path: str, rgb8: np.ndarray) -> None:
    """Write an (H, W, 3) uint8 image as PNG (through a temporary file)."""
    import OpenImageIO as oiio

    h, w, c = rgb8.shape
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(suffix=".png", prefix=".bounce-gi-", dir=directory)
    os.close(fd)
    try:
        out = oiio.ImageOutput.create(tmp)
        if out is None or not out.open(tmp, oiio.ImageSpec(w, h, c, oiio.UINT8)):
            raise OSError(f"cannot write {path}: {oiio.geterror()}")
        out.write_image(np.ascontiguousarray(rgb8))
        out.close()
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
