#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Build the Bounce GI extension zips: fetch the bundled wheels, validate, build per platform.

    python tools/package.py               # wheels -> validate -> dist/bounce_gi-<ver>-<platform>.zip
    python tools/package.py --wheels-only # just make sure ./wheels/ holds every wheel the manifest lists

The wheel list comes from `blender_manifest.toml` (single source of truth); each file name is
parsed into the `pip download` platform/python/abi flags, so adding a wheel there is enough.
Validation and building use `blender_ext.py`, which ships inside the bpy wheel (stdlib only), so
no Blender binary is needed. It is found by globbing site-packages, not by importing bpy (slow).
Every failure ends with exit status 1 and one line starting with "package.py: error:".
"""
from __future__ import annotations

import argparse
import glob
import os
import subprocess
import sys
import sysconfig
import tomllib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MANIFEST = os.path.join(ROOT, "blender_manifest.toml")


class PackageError(Exception):
    """A failure with a message meant for the user (printed as one line)."""


def read_manifest() -> dict:
    try:
        with open(MANIFEST, "rb") as fh:
            return tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as ex:
        raise PackageError(f"cannot read {MANIFEST}: {ex}") from None


def pip_flags_for_wheel(filename: str) -> tuple[str, str, list[str]]:
    """Split a wheel file name into (requirement, python version, pip download flags).

    `moderngl-5.13.0-cp311-cp311-win_amd64.whl` -> ("moderngl==5.13.0", "311", [...]).
    Compressed platform tags (`a.b.c`) are passed as several `--platform` flags; pip accepts a
    wheel matching any of them, and the downloaded name is then checked against the manifest.
    """
    parts = filename[:-len(".whl")].split("-")
    if len(parts) not in (5, 6):
        raise PackageError(f"wheel name does not follow the wheel spec: {filename}")
    dist, version, py_tag, abi_tag, plat_tag = parts[0], parts[1], parts[-3], parts[-2], parts[-1]
    if not py_tag.startswith("cp"):
        raise PackageError(f"only CPython wheels are supported, got {py_tag} in {filename}")
    flags = ["--implementation", "cp", "--python-version", py_tag[2:], "--abi", abi_tag]
    for plat in plat_tag.split("."):
        flags += ["--platform", plat]
    return f"{dist}=={version}", py_tag[2:], flags


def ensure_wheels(manifest: dict) -> list[str]:
    """Download every wheel the manifest lists that is not already present; return their paths."""
    wheels = manifest.get("wheels", [])
    if not wheels:
        return []
    paths = []
    for rel in wheels:
        path = os.path.normpath(os.path.join(ROOT, rel))
        paths.append(path)
        if os.path.isfile(path):
            continue
        dest = os.path.dirname(path)
        os.makedirs(dest, exist_ok=True)
        name = os.path.basename(path)
        req, _py, flags = pip_flags_for_wheel(name)
        cmd = [sys.executable, "-m", "pip", "download", "--quiet", "--disable-pip-version-check",
               "--retries", "2", "--timeout", "20",
               "--only-binary=:all:", "--no-deps", "--dest", dest, *flags, req]
        print(f"package.py: downloading {name}", flush=True)
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            # pip's last non-empty line is normally the useful one ("No matching distribution ...").
            lines = [l for l in (proc.stderr + proc.stdout).splitlines() if l.strip()]
            reason = lines[-1].strip() if lines else f"pip exited with {proc.returncode}"
            raise PackageError(f"pip download of {req} for {name} failed: {reason}")
        if not os.path.isfile(path):
            # pip found a wheel for these tags but with another name (e.g. a new manylinux tag set).
            got = sorted(os.path.basename(p) for p in glob.glob(os.path.join(dest, req.split("==")[0] + "-*")))
            raise PackageError(f"pip did not produce {name} (wheels/ holds: {', '.join(got) or 'nothing'}); "
                               f"update the name in blender_manifest.toml")
    return paths


def find_blender_ext() -> str:
    """Locate bl_pkg/cli/blender_ext.py inside the installed bpy wheel without importing bpy."""
    roots = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"], *sys.path}
    for root in sorted(r for r in roots if r and os.path.isdir(r)):
        hits = sorted(glob.glob(os.path.join(root, "bpy", "*", "scripts", "addons_core", "bl_pkg", "cli",
                                             "blender_ext.py")))
        if hits:
            return hits[-1]  # newest bpy/<version>/ when several are present
    raise PackageError("blender_ext.py not found: install the bpy wheel in this Python (make setup)")


def run_blender_ext(blender_ext: str, args: list[str], what: str) -> str:
    """Run blender_ext.py, echo its output, raise with its last line when it fails."""
    proc = subprocess.run([sys.executable, blender_ext, *args], capture_output=True, text=True, cwd=ROOT)
    out = (proc.stdout + proc.stderr).strip()
    if out:
        print(out, flush=True)
    if proc.returncode != 0:
        lines = [l for l in out.splitlines() if l.strip()]
        raise PackageError(f"{what} failed: {lines[-1].strip() if lines else f'exit status {proc.returncode}'}")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wheels-only", action="store_true", help="only download missing wheels into ./wheels/")
    parser.add_argument("--output-dir", default=os.path.join(ROOT, "dist"),
                        help="where the zips go (default: ./dist/)")
    args = parser.parse_args(argv)
    try:
        manifest = read_manifest()
        wheels = ensure_wheels(manifest)
        print(f"package.py: {len(wheels)} wheels present in {os.path.join(ROOT, 'wheels')}", flush=True)
        if args.wheels_only:
            return 0
        blender_ext = find_blender_ext()
        run_blender_ext(blender_ext, ["validate", ROOT], "manifest validation")
        out_dir = os.path.abspath(args.output_dir)
        # Start from an empty folder so stale zips of an older version never get shipped.
        prefix = f"{manifest['id']}-"
        for old in glob.glob(os.path.join(out_dir, prefix + "*.zip")):
            os.remove(old)
        os.makedirs(out_dir, exist_ok=True)
        run_blender_ext(blender_ext, ["build", "--source-dir", ROOT, "--output-dir", out_dir,
                                      "--split-platforms"], "extension build")
        zips = sorted(glob.glob(os.path.join(out_dir, prefix + "*.zip")))
        if len(zips) != len(manifest.get("platforms", [])):
            raise PackageError(f"expected one zip per platform {manifest.get('platforms')}, got {zips}")
        for z in zips:
            # A built zip must itself pass validation (catches excluded-but-needed files).
            run_blender_ext(blender_ext, ["validate", z], f"validation of {os.path.basename(z)}")
            print(f"package.py: built {os.path.relpath(z, ROOT)} ({os.path.getsize(z) // 1024} KiB)", flush=True)
    except PackageError as ex:
        print(f"package.py: error: {ex}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
