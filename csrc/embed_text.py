"""Write a C source that defines ``const char NAME[]``, the text of a file.

Usage: python embed_text.py INPUT OUTPUT NAME  (run by meson: csrc/meson.build)

The C core hands ode/fixed.h's text to the systems mechpy.symbolic generates
(mechpy._core.FIXED_STEPS_C), so that their fixed-step blocks are the engine's
own templates, from the build that runs them.
"""
import sys

src, out, name = sys.argv[1:4]
with open(src, encoding="ascii") as fh:
    lines = fh.read().splitlines()
quoted = ['"' + line.replace("\\", "\\\\").replace('"', '\\"') + '\\n"' for line in lines]
with open(out, "w", encoding="ascii") as fh:
    fh.write(f"/* Generated from {src.rsplit('/', 1)[-1]} by embed_text.py. */\n")
    fh.write(f"const char {name}[] =\n    " + "\n    ".join(quoted) + ";\n")
