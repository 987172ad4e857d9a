# SPDX-License-Identifier: GPL-3.0-or-later
"""The extension as users get it: manifest validates, zips build, the Linux zip installs into bpy,
enables (operator, panel, Scene property appear), disables cleanly; register() is repeatable.

Everything that imports bpy runs in a subprocess: BLENDER_USER_RESOURCES must be set before bpy is
imported (so nothing touches the user's Blender config), and register/unregister side effects
must not leak into other tests. Each subprocess prints what it sees; failures show that output.
Needs the bundled wheels: tools/package.py downloads them from PyPI when ./wheels/ lacks them.
"""
import glob
import os
import subprocess
import sys
import textwrap
import tomllib

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXT_MODULE = "bl_ext.user_default.bounce_gi"


def run_checked(cmd: list, env: dict | None = None, timeout: float = 120) -> str:
    """Run `cmd`; fail with its full output unless it exits 0. Returns stdout."""
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=ROOT,
                          env={**os.environ, **(env or {})})
    output = f"--- exit status {proc.returncode}\n--- stdout\n{proc.stdout}\n--- stderr\n{proc.stderr}"
    assert proc.returncode == 0, output
    return proc.stdout


def run_python(code: str, *args: str, env: dict | None = None, timeout: float = 120) -> str:
    """Run `code` in a fresh interpreter of this venv (see run_checked)."""
    return run_checked([sys.executable, "-c", textwrap.dedent(code), *args], env=env, timeout=timeout)


def blender_ext_path() -> str:
    sys.path.insert(0, os.path.join(ROOT, "tools"))
    try:
        import package
    finally:
        sys.path.pop(0)
    return package.find_blender_ext()


@pytest.fixture(scope="module")
def built_zips(tmp_path_factory):
    """Per-platform zips built by tools/package.py into a temporary folder (dist/ is left alone)."""
    out = tmp_path_factory.mktemp("dist")
    run_checked([sys.executable, os.path.join(ROOT, "tools", "package.py"), "--output-dir", str(out)], timeout=300)
    return {os.path.basename(p): p for p in glob.glob(os.path.join(out, "*.zip"))}


def test_manifest_fields():
    with open(os.path.join(ROOT, "blender_manifest.toml"), "rb") as fh:
        m = tomllib.load(fh)
    assert m["id"] == "bounce_gi" and m["type"] == "add-on"
    assert len(m["tagline"]) <= 64 and m["tagline"][-1].isalnum()
    assert set(m["platforms"]) == {"linux-x64", "windows-x64"}
    # Two CPython ABIs (Blender 4.2-5.0 and 5.1+) x two platforms x {moderngl, glcontext}.
    tags = {(w.split("-")[0].rsplit("/", 1)[-1], w.split("-")[2], "win" if "win_amd64" in w else "linux")
            for w in m["wheels"]}
    assert len(m["wheels"]) == 8 and len(tags) == 8, m["wheels"]


def test_manifest_validates(built_zips):
    # built_zips first: validation of a source folder also checks that the listed wheels exist.
    out = run_checked([sys.executable, blender_ext_path(), "validate", ROOT])
    assert "Success" in out, out


def test_zips_hold_only_their_platform(built_zips):
    import zipfile

    assert sorted(built_zips) == ["bounce_gi-0.1.0-linux_x64.zip", "bounce_gi-0.1.0-windows_x64.zip"]
    for name, path in built_zips.items():
        names = zipfile.ZipFile(path).namelist()
        wheels = [n for n in names if n.endswith(".whl")]
        assert len(wheels) == 4, (name, wheels)
        assert all(("win_amd64" in w) == ("windows" in name) for w in wheels), (name, wheels)
        assert {"__init__.py", "blender_manifest.toml", "ui/operators.py"} <= set(names), names
        # Nothing from development may ship.
        leaked = [n for n in names if n.split("/")[0] in {"tests", "tools", "examples", "dist", ".venv", ".git"}
                  or "__pycache__" in n or n.endswith(".pyc")]
        assert not leaked, leaked


def test_zip_holds_what_the_extension_imports(built_zips):
    """The zip ships exactly the modules the extension's entry point imports (directly or through others,
    function-level imports included), its shaders, the quality table, the manifest, the licence and the wheels:
    no developer tooling, nothing missing."""
    import zipfile

    sys.path.insert(0, os.path.join(ROOT, "tests"))
    try:
        from support import import_graph
    finally:
        sys.path.pop(0)
    used = {str(import_graph.FILES[m].relative_to(import_graph.ROOT)) for m in import_graph.reachable("bounce_gi")}
    shaders = {os.path.relpath(p, ROOT) for p in glob.glob(os.path.join(ROOT, "gpu_kernels/shaders/*/*.glsl"))}
    names = set(zipfile.ZipFile(built_zips["bounce_gi-0.1.0-linux_x64.zip"]).namelist())
    files = {n for n in names if not n.endswith("/")}
    shipped_py = {n for n in files if n.endswith(".py")}
    print("imported but not shipped", sorted(used - shipped_py), "shipped but never imported",
          sorted(shipped_py - used))
    assert shipped_py == used
    other = files - shipped_py - shaders - {n for n in files if n.startswith("wheels/") and n.endswith(".whl")}
    assert shaders <= files and other == {"blender_manifest.toml", "LICENSE", "addon/quality_front.json",
                                          "gpu_kernels/common/ggx_tables.npz"}, other
    assert len(used) > 40  # the entry point's imports were found (a wrong root would find one module)


def test_install_enable_disable(built_zips, tmp_path):
    code = """
        import os, sys
        import bpy
        zip_path, mod = sys.argv[1], sys.argv[2]
        res = os.environ["BLENDER_USER_RESOURCES"]
        print("blender", bpy.app.version_string, "extensions dir", bpy.utils.user_resource("EXTENSIONS"))
        assert bpy.utils.user_resource("EXTENSIONS").startswith(res), "BLENDER_USER_RESOURCES ignored"

        print("install", bpy.ops.extensions.package_install_files(
            filepath=zip_path, repo="user_default", enable_on_install=True))
        print("enabled add-ons", list(bpy.context.preferences.addons.keys()))
        assert mod in bpy.context.preferences.addons, "extension not enabled"
        print("module file", sys.modules[mod].__file__)
        assert sys.modules[mod].__file__.startswith(res), "imported from outside the install"
        assert hasattr(bpy.types, "BOUNCE_GI_OT_render_preview")
        print("operator", bpy.ops.bounce_gi.render_preview.get_rna_type().identifier)
        assert hasattr(bpy.types.Scene, "bounce_gi")
        print("scene settings", bpy.context.scene.bounce_gi.method, bpy.context.scene.bounce_gi.output_path)
        assert hasattr(bpy.types, "VIEW3D_PT_bounce_gi") and hasattr(bpy.types, "VIEW3D_PT_bounce_gi_last_render")

        # The bundled wheels were unpacked for this Python, and they work (not the venv's copy).
        site = os.path.join(res, "extensions", ".local", "lib",
                            "python%d.%d" % sys.version_info[:2], "site-packages")
        print("bundled site-packages", sorted(os.listdir(site)))
        sys.path.insert(0, site)
        import moderngl, glcontext
        print("moderngl from", moderngl.__file__)
        assert moderngl.__file__.startswith(site) and glcontext.__file__.startswith(site)

        # The installed copy renders (relative imports under bl_ext.*, shaders shipped, bundled moderngl).
        cam = bpy.data.objects.new("Cam", bpy.data.cameras.new("Cam"))
        cam.location, cam.rotation_euler = (7.0, -7.0, 5.0), (1.1, 0.0, 0.785)
        bpy.context.scene.collection.objects.link(cam)
        bpy.context.scene.camera = cam
        r = bpy.context.scene.render
        r.resolution_x, r.resolution_y, r.resolution_percentage = 40, 30, 100
        print("render", bpy.ops.bounce_gi.render_preview())
        img = bpy.data.images["Bounce GI Preview"]
        print("image", tuple(img.size), "engine module", sys.modules[mod + ".gpu_kernels.engine"].__file__)
        assert tuple(img.size) == (20, 15)

        print("disable", bpy.ops.preferences.addon_disable(module=mod))
        assert mod not in bpy.context.preferences.addons
        assert not hasattr(bpy.types, "BOUNCE_GI_OT_render_preview")
        assert not hasattr(bpy.types.Scene, "bounce_gi")
        assert not hasattr(bpy.types, "VIEW3D_PT_bounce_gi")
        print("OK")
    """
    out = run_python(code, built_zips["bounce_gi-0.1.0-linux_x64.zip"], EXT_MODULE,
                     env={"BLENDER_USER_RESOURCES": str(tmp_path)})
    print(out)
    assert out.rstrip().endswith("OK"), out


def package_path_env(tmp_path) -> dict:
    """PYTHONPATH under which `import bounce_gi` is this checkout (installed or not)."""
    (tmp_path / "pkg").mkdir()
    os.symlink(ROOT, tmp_path / "pkg" / "bounce_gi")
    return {"PYTHONPATH": str(tmp_path / "pkg")}


def test_register_unregister_twice(tmp_path):
    code = """
        import bpy
        import bounce_gi
        for round_ in range(2):
            bounce_gi.register()
            assert hasattr(bpy.types.Scene, "bounce_gi") and hasattr(bpy.types, "BOUNCE_GI_OT_render_preview")
            s = bpy.context.scene.bounce_gi
            assert (s.method, s.quality, s.resolution_percentage, s.output_path) == ("AUTO", "MEDIUM", 50, "")
            assert hasattr(bpy.types, "BOUNCE_GI_OT_toggle_overlay")
            assert bounce_gi.ui.render_engine.BounceGIRenderEngine.is_registered
            assert "BOUNCE_GI" in bpy.types.DATA_PT_light.COMPAT_ENGINES
            bounce_gi.unregister()
            assert not bounce_gi.ui.render_engine.BounceGIRenderEngine.is_registered
            assert "BOUNCE_GI" not in bpy.types.DATA_PT_light.COMPAT_ENGINES
            assert not hasattr(bpy.types.Scene, "bounce_gi")
            assert not hasattr(bpy.types, "BOUNCE_GI_OT_render_preview")
            assert not hasattr(bpy.types, "VIEW3D_PT_bounce_gi")
            assert not [h for h in (*bpy.app.handlers.load_post, *bpy.app.handlers.load_pre,
                                    *bpy.app.handlers.depsgraph_update_post) if h.__module__.startswith("bounce_gi")]
            assert not hasattr(bpy.types, "BOUNCE_GI_OT_toggle_overlay")
            print("round", round_, "OK")
    """
    out = run_python(code, env={**package_path_env(tmp_path), "BLENDER_USER_RESOURCES": str(tmp_path)})
    assert "round 1 OK" in out, out


def test_package_import_does_not_import_bpy(tmp_path):
    # The root __init__ is also the extension entry point; it must stay free of bpy at import.
    code = """
        import sys
        import bounce_gi, bounce_gi.gpu_kernels
        assert "bpy" not in sys.modules, "importing bounce_gi imported bpy"
        print("OK")
    """
    assert "OK" in run_python(code, env=package_path_env(tmp_path))
