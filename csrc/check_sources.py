"""Exit 1 (naming the files) if a C source under csrc/ is not in csrc/meson.build.

Usage: python check_sources.py CSRC_DIR LISTED_FILE...  (run by meson at configure time)
"""
import sys
from pathlib import Path

root = Path(sys.argv[1]).resolve()
listed = {Path(p).resolve() for p in sys.argv[2:]}
missing = sorted(str(p.relative_to(root)) for p in root.rglob("*.c") if p.resolve() not in listed)
if missing:
    sys.exit("C sources not listed in csrc/meson.build (add one line each): " + ", ".join(missing))
