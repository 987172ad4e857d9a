# SPDX-License-Identifier: GPL-3.0-or-later
"""gpu_kernels.shader_preprocessor: includes, pragma once, defines, stages, line mapping, logs."""
from pathlib import Path

import pytest

from gpu_kernels.gl import preprocessor as sp
from gpu_kernels.gl.preprocessor import GENERATED, ShaderIncludeError


def write(root: Path, rel: str, text: str) -> Path:
    p = root / rel
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)
    return p.resolve()


def body(src) -> list[str]:
    """Output lines after the header, minus blanks: what came from files."""
    return [l for l in src.text.splitlines() if l.strip()]


def out_line(src, text: str) -> int:
    """1-based output line number of the only line equal to ``text``."""
    hits = [i for i, l in enumerate(src.text.splitlines(), 1) if l == text]
    assert len(hits) == 1, (text, hits)
    return hits[0]


def test_nested_includes_relative_to_including_file(tmp_path):
    write(tmp_path, "lib/b.glsl", "float b() { return 2.0; }\n")
    write(tmp_path, "lib/a.glsl", '#include "b.glsl"\nfloat a() { return b(); }\n')
    top = write(tmp_path, "top.glsl", '#include "lib/a.glsl"\nvoid main() {}\n')
    src = sp.preprocess(top)
    assert src.text.splitlines() == [
        "#version 430 core",
        "float b() { return 2.0; }",
        "float a() { return b(); }",
        "void main() {}",
    ]
    assert "#include" not in src.text


def test_include_falls_back_to_search_dirs(tmp_path):
    write(tmp_path, "common/util.glsl", "const float PI = 3.14159;\n")
    top = write(tmp_path, "src/top.glsl", '#include "util.glsl"\n')
    src = sp.preprocess(top, search_dirs=[tmp_path / "common"])
    assert src.text.splitlines()[1] == "const float PI = 3.14159;"
    assert src.line_map[1] == (str((tmp_path / "common/util.glsl").resolve()), 1)


def test_bare_name_found_in_search_dirs(tmp_path):
    write(tmp_path, "src/top.glsl", "void main() {}\n")
    src = sp.preprocess("top.glsl", search_dirs=[tmp_path / "src"])
    assert src.line_map[1] == (str((tmp_path / "src/top.glsl").resolve()), 1)
    with pytest.raises(FileNotFoundError):
        sp.preprocess("nope.glsl", search_dirs=[tmp_path / "src"])


def test_pragma_once_top_level_included_once(tmp_path):
    write(tmp_path, "once.glsl", "#pragma once\nstruct Light { vec3 c; };\n")
    write(tmp_path, "plain.glsl", "float twice;\n")
    write(tmp_path, "mid.glsl", '#include "once.glsl"\n')
    top = write(tmp_path, "top.glsl",
                '#include "once.glsl"\n#include "mid.glsl"\n#include "once.glsl"\n'
                '#include "plain.glsl"\n#include "plain.glsl"\n')
    lines = sp.preprocess(top).text.splitlines()
    assert lines.count("struct Light { vec3 c; };") == 1
    assert lines.count("float twice;") == 2  # no pragma: included every time
    assert not any("pragma" in l for l in lines)


def test_pragma_once_inside_stage_blocks_is_guarded_not_dropped(tmp_path):
    # Conditionals are not evaluated, so dropping the second copy would leave the fragment
    # stage without the include; it must be emitted again under a macro guard instead.
    write(tmp_path, "once.glsl", "#pragma once\nfloat shared_fn();\n")
    top = write(tmp_path, "prog.glsl",
                "#if defined(VERTEX_SHADER)\n#include \"once.glsl\"\n#endif\n"
                "#if defined(FRAGMENT_SHADER)\n#include \"once.glsl\"\n#endif\n"
                '#include "once.glsl"\n#include "once.glsl"\n')
    src = sp.preprocess(top, stage="fragment")
    lines = src.text.splitlines()
    # two guarded copies in the blocks, one more at top level, then the last is dropped
    assert lines.count("float shared_fn();") == 3
    assert lines.count("#ifndef BOUNCE_ONCE_0") == 3
    assert lines.count("#define BOUNCE_ONCE_0") == 3
    i = lines.index("#if defined(FRAGMENT_SHADER)")
    assert lines[i + 1:i + 6] == ["#ifndef BOUNCE_ONCE_0", "#define BOUNCE_ONCE_0",
                                  "float shared_fn();", "#endif", "#endif"]
    assert len(src.line_map) == len(lines)
    assert src.line_map[i + 1] == (GENERATED, i + 2)


def test_define_injection_order_and_formatting(tmp_path):
    top = write(tmp_path, "t.glsl", "void main() {}\n")
    src = sp.preprocess(top, defines={"ZETA": 3, "ALPHA": None, "MODE_SUN": True, "OFF": False,
                                      "SCALE": 0.5}, stage="vertex")
    assert src.text.splitlines() == [
        "#version 430 core",
        "#define ZETA 3",
        "#define ALPHA",
        "#define MODE_SUN 1",
        "#define OFF 0",
        "#define SCALE 0.5",
        "#define VERTEX_SHADER",
        "void main() {}",
    ]
    assert src.line_map[:7] == [(GENERATED, i) for i in range(1, 8)]
    assert src.line_map[7] == (str(top), 1)


@pytest.mark.parametrize("bad", [{"1X": 1}, {"A B": 1}, {"X": "1\n#define Y"}])
def test_bad_defines_rejected(tmp_path, bad):
    top = write(tmp_path, "t.glsl", "void main() {}\n")
    with pytest.raises(ValueError):
        sp.preprocess(top, defines=bad)


@pytest.mark.parametrize("stage,macro", [("vertex", "VERTEX_SHADER"), ("Fragment", "FRAGMENT_SHADER"),
                                         ("geometry", "GEOMETRY_SHADER"), ("COMPUTE_SHADER", "COMPUTE_SHADER")])
def test_stage_define(tmp_path, stage, macro):
    top = write(tmp_path, "t.glsl", "void main() {}\n")
    lines = sp.preprocess(top, defines={"A": 1}, stage=stage).text.splitlines()
    assert lines[2] == f"#define {macro}"
    assert sum(l.endswith("_SHADER") for l in lines) == 1


def test_unknown_stage(tmp_path):
    top = write(tmp_path, "t.glsl", "void main() {}\n")
    with pytest.raises(ValueError, match="tessellation"):
        sp.preprocess(top, stage="tessellation")


def test_own_version_is_hoisted_and_stripped(tmp_path):
    write(tmp_path, "inc.glsl", "#version 450  core\nfloat x;\n")  # same version, spacing differs
    top = write(tmp_path, "t.glsl", '// header comment\n#version 450 core\n#include "inc.glsl"\nvoid main() {}\n')
    src = sp.preprocess(top, defines={"A": 1})
    lines = src.text.splitlines()
    assert lines[:4] == ["#version 450 core", "#define A 1", "// header comment", "float x;"]
    assert sum("#version" in l for l in lines) == 1
    assert src.line_map[0] == (str(top), 2)


def test_conflicting_version_in_include(tmp_path):
    inc = write(tmp_path, "inc.glsl", "#version 330\n")
    top = write(tmp_path, "t.glsl", '#version 430 core\n#include "inc.glsl"\n')
    with pytest.raises(ShaderIncludeError, match=f"{inc}:1"):
        sp.preprocess(top)


def test_missing_include_names_file_and_line(tmp_path):
    top = write(tmp_path, "t.glsl", 'float a;\n\n#include "nowhere/missing.glsl"\n')
    with pytest.raises(ShaderIncludeError) as e:
        sp.preprocess(top)
    assert str(e.value).startswith(f"{top}:3: ")
    assert "nowhere/missing.glsl" in str(e.value)


def test_missing_include_in_nested_file(tmp_path):
    inc = write(tmp_path, "sub/inc.glsl", 'float a;\n#include "gone.glsl"\n')
    top = write(tmp_path, "t.glsl", '#include "sub/inc.glsl"\n')
    with pytest.raises(ShaderIncludeError, match=f"^{inc}:2: .*gone.glsl"):
        sp.preprocess(top)


def test_malformed_include(tmp_path):
    top = write(tmp_path, "t.glsl", "#include <lib.glsl>\n")
    with pytest.raises(ShaderIncludeError, match=f"{top}:1: malformed"):
        sp.preprocess(top)


def test_cycle_detected_with_chain(tmp_path):
    a = write(tmp_path, "a.glsl", '#pragma once\n#include "b.glsl"\n')
    b = write(tmp_path, "b.glsl", '#pragma once\n#include "a.glsl"\n')
    top = write(tmp_path, "top.glsl", '#include "a.glsl"\n')
    with pytest.raises(ShaderIncludeError, match="cycle") as e:
        sp.preprocess(top)
    assert f"{top} -> {a} -> {b} -> {a}" in str(e.value)
    assert str(e.value).startswith(f"{b}:2: ")


def test_self_include_is_a_cycle(tmp_path):
    top = write(tmp_path, "self.glsl", '#include "self.glsl"\n')
    with pytest.raises(ShaderIncludeError, match="cycle"):
        sp.preprocess(top)


def test_depth_limit(tmp_path):
    for i in range(3):
        write(tmp_path, f"d{i}.glsl", f'float d{i};\n#include "d{i + 1}.glsl"\n')
    write(tmp_path, "d3.glsl", "float d3;\n")
    top = write(tmp_path, "top.glsl", '#include "d0.glsl"\n')  # d3 sits at include depth 4
    assert body(sp.preprocess(top, max_depth=4))[1:] == ["float d0;", "float d1;", "float d2;", "float d3;"]
    with pytest.raises(ShaderIncludeError, match="max_depth=3") as e:
        sp.preprocess(top, max_depth=3)
    assert str(e.value).startswith(f"{(tmp_path / 'd2.glsl').resolve()}:2: ")
    assert "d3.glsl" in str(e.value)


def test_line_map_points_into_included_file(tmp_path):
    inc = write(tmp_path, "lib/inc.glsl", "// helpers\n\nfloat helper() {\n    return undefined_thing;\n}\n")
    top = write(tmp_path, "top.glsl", '#version 430 core\n#include "lib/inc.glsl"\nvoid main() {\n  bad;\n}\n')
    src = sp.preprocess(top, defines={"A": 1, "B": 2}, stage="compute")
    n = out_line(src, "    return undefined_thing;")
    assert n == 8  # version + 2 defines + stage + 4 lines of inc.glsl
    assert src.origin(n) == (str(inc), 4)
    assert src.origin(out_line(src, "  bad;")) == (str(top), 4)
    assert src.origin(0) is None and src.origin(len(src.line_map) + 1) is None
    assert len(src.line_map) == len(src.text.splitlines())


def _lib_and_source(tmp_path):
    # padding pushes output line numbers past 9, so multi-digit parsing is exercised
    inc = write(tmp_path, "inc.glsl", "//\n" * 10 + "float f() {\n    return nope;\n}\n")
    top = write(tmp_path, "top.glsl", '#include "inc.glsl"\nvoid main() {\n    x = 1;\n}\n')
    src = sp.preprocess(top, defines={"MODE_SUN": None})
    return inc, top, src


def test_format_mesa_log(tmp_path):
    inc, top, src = _lib_and_source(tmp_path)
    bad = out_line(src, "    return nope;")
    main = out_line(src, "    x = 1;")
    log = (f"0:{bad}(12): error: `nope' undeclared\n"
           f"0:{main}(5): warning: something\n"
           "some summary line\n"
           "0:999(1): error: beyond the end")
    assert sp.format_compile_error(log, src).splitlines() == [
        f"{inc}:12: error: `nope' undeclared",
        f"{top}:3: warning: something",
        "some summary line",
        "0:999(1): error: beyond the end",
    ]


def test_format_nvidia_and_amd_logs(tmp_path):
    inc, top, src = _lib_and_source(tmp_path)
    bad = out_line(src, "    return nope;")
    log = (f"0({bad}) : error C1008: undefined variable \"nope\"\n"
           f"ERROR: 0:{bad}: 'nope' : undeclared identifier\n"
           "0(x) : not a line")
    assert sp.format_compile_error(log, src).splitlines() == [
        f"{inc}:12: error C1008: undefined variable \"nope\"",
        f"{inc}:12: ERROR: 'nope' : undeclared identifier",
        "0(x) : not a line",
    ]


def test_format_error_on_generated_line_shows_it(tmp_path):
    top = write(tmp_path, "t.glsl", "void main() {}\n")
    src = sp.preprocess(top, defines={"BAD": "((("})
    msg = sp.format_compile_error("0:2(1): error: syntax error", src)
    assert msg.startswith(f"{GENERATED}:2: error: syntax error")
    assert "#define BAD (((" in msg


def test_load_uses_shader_dir(tmp_path, monkeypatch):
    write(tmp_path, "common/math.glsl", "#pragma once\nfloat sq(float x) { return x * x; }\n")
    write(tmp_path, "passes/sky.glsl",
          '#include "common/math.glsl"\n'
          "#if defined(VERTEX_SHADER)\nvoid main() { gl_Position = vec4(0.0); }\n#endif\n"
          "#if defined(FRAGMENT_SHADER)\nout vec4 c;\nvoid main() { c = vec4(sq(2.0)); }\n#endif\n")
    monkeypatch.setattr(sp, "SHADER_DIR", tmp_path)
    src = sp.load("passes/sky.glsl", defines={"MODE_SUN": 1}, stage="fragment")
    assert src.text.splitlines()[:4] == ["#version 430 core", "#define MODE_SUN 1",
                                         "#define FRAGMENT_SHADER", "float sq(float x) { return x * x; }"]
    prog = sp.load_program("passes/sky.glsl")
    assert sorted(prog) == ["fragment_shader", "vertex_shader"]
    assert "#define VERTEX_SHADER" in prog["vertex_shader"].text
    # every stage of one file shares a line_map, so any of them can map a program's log
    assert prog["vertex_shader"].line_map == prog["fragment_shader"].line_map


def test_load_program_without_stage_blocks(tmp_path, monkeypatch):
    write(tmp_path, "k.glsl", "layout(local_size_x = 8) in;\nvoid main() {}\n")
    monkeypatch.setattr(sp, "SHADER_DIR", tmp_path)
    with pytest.raises(ValueError, match="no #if defined"):
        sp.load_program("k.glsl")


def test_default_shader_dir():
    assert sp.SHADER_DIR == Path(sp.__file__).parent.parent / "shaders"


def test_every_volume_pass_declares_the_work_group_dispatch_assumes():
    """gl/bind.dispatch covers a volume with VOLUME_GROUP-sized groups unless told otherwise: a shader that declared
    another 3D group would leave voxels unvisited (or visit them twice). Every compute layout naming local_size_z
    declares VOLUME_GROUP."""
    import re

    from gpu_kernels.gl.bind import VOLUME_GROUP

    root = Path(sp.__file__).resolve().parents[1] / "shaders"
    layout = re.compile(r"layout\(local_size_x = (\d+), local_size_y = (\d+), local_size_z = (\d+)\) in;")
    found = [(path.name, tuple(int(v) for v in m.groups())) for path in sorted(root.rglob("*.glsl"))
             for m in layout.finditer(path.read_text())]
    assert len(found) >= 10, found  # the volume passes of voxel/, lpv/ and vct/
    assert all(group == VOLUME_GROUP for _, group in found), found
