"""Embed the text of files at build time (run by meson: csrc/meson.build).

Usage:
  python embed_text.py INPUT OUTPUT NAME
      a C source that defines ``const char NAME[]``, INPUT's text.  The C core
      hands ode/fixed.h's text to the systems mechpy.symbolic generates
      (mechpy._core.FIXED_STEPS_C), so that their fixed-step blocks are the
      engine's own templates, from the build that runs them.
  python embed_text.py --python OUTPUT INPUT...
      a Python module with one string constant per INPUT, named after its file
      (gen/lu_lanes.h: LU_LANES), its text.  The C that every generated system
      shares (csrc/gen/*.h: the dense LU, the lane solver, ...) is kept as real
      C files, compiled by tests/test_compiled.py, and reaches
      mechpy.symbolic.codegen as mechpy.symbolic._ctext.
"""
import sys


def _lines(src):
    with open(src, encoding="ascii") as fh:
        return fh.read().splitlines()


def _base(src):
    return src.replace("\\", "/").rsplit("/", 1)[-1]


if sys.argv[1] == "--python":
    out, srcs = sys.argv[2], sys.argv[3:]
    with open(out, "w", encoding="ascii") as fh:
        fh.write(f'"""Generated from {", ".join(map(_base, srcs))} by embed_text.py."""\n')
        for src in srcs:
            name = _base(src).split(".")[0].upper()
            quoted = [repr(line + "\n") for line in _lines(src)]
            fh.write(f"\n{name} = (\n    " + "\n    ".join(quoted) + "\n)\n")
else:
    src, out, name = sys.argv[1:4]
    quoted = ['"' + line.replace("\\", "\\\\").replace('"', '\\"') + '\\n"'
              for line in _lines(src)]
    with open(out, "w", encoding="ascii") as fh:
        fh.write(f"/* Generated from {_base(src)} by embed_text.py. */\n")
        fh.write(f"const char {name}[] =\n    " + "\n    ".join(quoted) + ";\n")
