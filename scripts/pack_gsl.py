"""meson dist script: put GSL's source tarball into the sdist, so that it builds offline.

meson.build runs this at `meson dist` (which `python -m build --sdist` calls through
meson-python).  The tarball subprojects/gsl.wrap names is copied into the distribution's
subprojects/packagecache/, where meson looks before it downloads: an sdist built on a
machine without GSL then configures and builds with no network (meson checks the
tarball's sha256 against the wrap as for a download).  The tarball is taken from the
source tree's subprojects/packagecache/ (where a fallback build has left it), else
downloaded once from the wrap's source_url into that cache; either way its sha256 must
be the wrap's, else the sdist fails here rather than at a user's install.
"""
import hashlib
import os
import re
import shutil
import sys
import urllib.request
from pathlib import Path


def wrap_fields(wrap: Path) -> dict:
    """The [wrap-file] keys of a meson wrap (key = value lines)."""
    return dict(re.findall(r"^(\w+)\s*=\s*(\S+)\s*$", wrap.read_text(), flags=re.M))


def main() -> int:
    src = Path(os.environ["MESON_SOURCE_ROOT"])
    dist = Path(os.environ["MESON_DIST_ROOT"])
    wrap = wrap_fields(src / "subprojects" / "gsl.wrap")
    name, want = wrap["source_filename"], wrap["source_hash"]
    cache = src / "subprojects" / "packagecache"
    tarball = cache / name
    if not tarball.is_file():
        print(f"pack_gsl: downloading {wrap['source_url']} into {cache}", flush=True)
        cache.mkdir(parents=True, exist_ok=True)
        part = tarball.with_suffix(".part")
        try:
            with urllib.request.urlopen(wrap["source_url"], timeout=120) as r, \
                    open(part, "wb") as f:
                shutil.copyfileobj(r, f)
        except OSError as e:
            part.unlink(missing_ok=True)
            print(f"pack_gsl: cannot download GSL's source ({e}); put {name} in {cache}",
                  file=sys.stderr)
            return 1
        part.replace(tarball)
    got = hashlib.sha256(tarball.read_bytes()).hexdigest()   # (7 MB)
    if got != want:
        print(f"pack_gsl: {tarball} has sha256 {got}, subprojects/gsl.wrap says {want}",
              file=sys.stderr)
        return 1
    out = dist / "subprojects" / "packagecache"
    out.mkdir(parents=True, exist_ok=True)
    shutil.copy2(tarball, out / name)
    print(f"pack_gsl: {name} ({tarball.stat().st_size} bytes, sha256 checked) in the sdist")
    return 0


if __name__ == "__main__":
    sys.exit(main())
