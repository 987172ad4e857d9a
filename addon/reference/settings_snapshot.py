# SPDX-License-Identifier: GPL-3.0-or-later
"""Every render setting of a scene, remembered and put back exactly: what a Cycles reference may change (engine,
samples, resolution, film, output format, the view layer's passes ...) and what Blender changes along with it
(switching the file format resets colour mode, codec and depth to what the new format supports).

A snapshot holds each plain property (bool, int, float, string, enum, and their arrays) of the scene's render
settings, their image settings with its colour management, the Cycles settings and the view layer with its Cycles
settings. `restore` sets back only what differs, in rounds, because one setting can reset another (a file format
change resets the colour depth): it stops when all are equal again.
"""
from __future__ import annotations

PLAIN = {"BOOLEAN", "INT", "FLOAT", "STRING", "ENUM"}
RESTORE_ROUNDS = 4


def settings_structs(scene, view_layer) -> list:
    """The structs a reference render may touch, in the order they are restored (the engine first: it decides
    which engine's settings exist)."""
    r = scene.render
    im = r.image_settings
    structs = [r, im, im.view_settings, im.display_settings, getattr(scene, "cycles", None), view_layer,
               getattr(view_layer, "cycles", None)]
    return [s for s in structs if s is not None]


def plain_values(struct) -> dict:
    """{property name: value} for every writable plain property of an RNA struct (arrays as tuples)."""
    values = {}
    for prop in struct.bl_rna.properties:
        if prop.is_readonly or prop.type not in PLAIN or prop.identifier == "rna_type":
            continue
        try:
            value = getattr(struct, prop.identifier)
        except AttributeError:
            continue
        values[prop.identifier] = tuple(value) if getattr(prop, "is_array", False) else value
    return values


def snapshot(scene, view_layer) -> list:
    """[(struct, {name: value})] of every render setting (see the module docstring)."""
    return [(struct, plain_values(struct)) for struct in settings_structs(scene, view_layer)]


def differences(snap: list) -> list:
    """(struct path, name, saved value, current value) for every setting that is not as saved."""
    out = []
    for struct, values in snap:
        now = plain_values(struct)
        out += [(struct.path_from_id() if hasattr(struct, "path_from_id") else repr(struct), name, value,
                 now.get(name)) for name, value in values.items() if now.get(name) != value]
    return out


def restore(snap: list) -> list:
    """Put every setting of `snap` back; returns the differences that remain (none, unless Blender refuses)."""
    for _ in range(RESTORE_ROUNDS):
        changed = False
        for struct, values in snap:
            now = plain_values(struct)
            for name, value in values.items():
                if now.get(name) != value:
                    try:
                        setattr(struct, name, value)
                        changed = True
                    except (AttributeError, TypeError, ValueError):
                        pass
        if not changed:
            break
    return differences(snap)
