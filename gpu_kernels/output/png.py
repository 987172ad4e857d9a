# SPDX-License-Identifier: GPL-3.0-or-later
"""An image for people: scene-linear RGB through Blender's Standard view transform (the sRGB curve, clipped) into an
8-bit PNG, written atomically."""
from __future__ import annotations

import os
import tempfile

import numpy as np


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) of values clipped to [0, 1]."""
    x = np.clip(np.asarray(linear, np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def write_png(path: str, image: np.ndarray) -> None:
    """(H, W, 3|4) scene-linear float, rows top-to-bottom, as an 8-bit RGB PNG."""
    import OpenImageIO as oiio

    rgb = np.round(srgb_encode(np.asarray(image)[..., :3]) * 255).astype(np.uint8)
    h, w = rgb.shape[:2]
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(suffix=".png", prefix=".bounce-gi-", dir=directory)
    os.close(fd)
    try:
        out = oiio.ImageOutput.create(tmp)
        if out is None or not out.open(tmp, oiio.ImageSpec(w, h, 3, oiio.UINT8)):
            raise OSError(f"cannot write {path}: {oiio.geterror()}")
        ok = out.write_image(np.ascontiguousarray(rgb))
        out.close()
        if not ok:
            raise OSError(f"cannot write {path}: {out.geterror()}")
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
