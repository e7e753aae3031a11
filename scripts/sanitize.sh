#!/usr/bin/env bash
# Run the test suite against mechpy's C core built with AddressSanitizer and
# UndefinedBehaviorSanitizer (any report fails the run).
#
#   bash scripts/sanitize.sh [pytest args]      # PYTHON=... to choose the interpreter
#
# The sanitized extension is meson's own sanitizer build (-Db_sanitize=address,undefined;
# meson.build adds float-cast-overflow and makes undefined behaviour fatal) in
# build/asan/meson; ninja rebuilds what changed.  Its _core*.so goes into a copy of
# the package in build/asan/mechpy; the normal (editable) build is not touched.
# Python is not sanitized, so gcc's libasan is preloaded.  Leaks: LeakSanitizer
# runs at the end of the session inside the live interpreter (tests/conftest.py),
# where everything Python still holds is reachable, so only blocks nobody points to
# any more are reported; the exit-time check (interpreter teardown noise) is off.
set -euo pipefail
cd "$(dirname "$0")/.."
py=${PYTHON:-python3}
out=build/asan
say() { printf 'mechpy sanitize: %s\n' "$*"; }

# meson and ninja: those beside the interpreter (the dev.sh .venv), else on PATH
bindir=$(dirname "$(command -v "$py")")
meson=$bindir/meson; [ -x "$meson" ] || meson=$(command -v meson) ||
    { say "meson not found (pip install meson ninja)"; exit 1; }
[ -x "$bindir/ninja" ] && export PATH="$bindir:$PATH"
if [ ! -f "$out/meson/build.ninja" ]; then
    say "configuring the ASan+UBSan build in $out/meson"
    rm -rf "$out"; mkdir -p "$out"
    "$meson" setup "$out/meson" -Db_sanitize=address,undefined -Db_lundef=false \
        -Doptimization=1 -Ddebug=true -Dpython.install_env=auto >"$out/setup.log" 2>&1 ||
        { cat "$out/setup.log"; say "meson setup failed"; exit 1; }
fi
"$meson" compile -C "$out/meson" >"$out/compile.log" 2>&1 ||
    { cat "$out/compile.log"; say "the ASan+UBSan build failed"; exit 1; }
grep -E 'warning:|error:' "$out/compile.log" || true
# the package: Python sources copied every run (cheap), next to the sanitized .so
rm -rf "$out/mechpy"
(cd mechpy && find . -type f -not -path '*/__pycache__/*' -not -name '*.so' -print0 |
    xargs -0 -I{} install -D -m 644 {} "../$out/mechpy/{}")
cp "$out"/meson/_core*.so "$out/mechpy/"
# what the build generates into the package (the C every generated system shares)
cp "$out"/meson/csrc/_ctext.py "$out/mechpy/symbolic/"
# the editable install's import hook (a .pth in .venv) would load the normal build:
# a sitecustomize on PYTHONPATH removes it, in this interpreter and its children
mkdir -p "$out/site"
cat > "$out/site/sitecustomize.py" <<'PY'
import sys
# (meson-python names the hook after the distribution: _mechpy_classical_editable_loader)
sys.meta_path[:] = [f for f in sys.meta_path
                    if not (type(f).__module__.startswith("_mechpy")
                            and type(f).__module__.endswith("_editable_loader"))]
PY

libasan=$(gcc -print-file-name=libasan.so)
[ -e "$libasan" ] || { say "gcc's libasan.so not found (Debian: apt-get install gcc)"; exit 1; }
# libstdc++ too: loaded before ASan initialises, its __cxa_throw interceptor works
# (C++ extensions such as matplotlib's ft2font throw during import).
libstdcxx=$(gcc -print-file-name=libstdc++.so)
export LD_PRELOAD="$libasan${libstdcxx:+ $libstdcxx}"
# intercept_tls_get_addr=0: the __tls_get_addr interceptor of GCC <= 13's runtime (Debian 12
# has GCC 12) takes a dynamic TLS block that starts 16 bytes past a page boundary for a
# glibc 2.19 block with a header, and records the two words before it (here: ASan's own
# chunk header, as every large ASan allocation starts there) as that block's start and
# size.  LeakSanitizer's tracer then scans that garbage range at the leak check and dies
# ("Tracer caught signal 11").  Without the interceptor the blocks are still found as
# heap chunks reachable from each thread's dtv, so no root is lost.
export ASAN_OPTIONS="detect_leaks=1:leak_check_at_exit=0:abort_on_error=1:halt_on_error=1:detect_stack_use_after_return=0:allocator_may_return_null=1:intercept_tls_get_addr=0:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
export PYTHONMALLOC=malloc          # every allocation visible to ASan/LSan
export PYTHONPATH="$PWD/$out:$PWD/$out/site${PYTHONPATH:+:$PYTHONPATH}"
export PYTHONSAFEPATH=1           # no cwd on sys.path: the copy in build/asan is imported
export MECHPY_SANITIZED=1
# A sample of the suite, every C path still exercised; the rest runs in the normal pass
# only (scripts/dev.sh test runs both, side by side):
# - the notebooks run in Jupyter kernels (a third interpreter each, slow under ASan) and
#   call the same C paths as the tests;
# - tests/test_plot.py (Matplotlib drawing) and tests/test_cluster.py (Dask worker
#   processes) are Python layers over solve/solve_many, which their own tests run here;
# - the cases marked `slow` repeat a C path of a faster case at a tighter tolerance or a
#   larger size (SciPy's side in Python takes most of their time).
# MECHPY_SANITIZE_ALL=1 runs everything but the notebooks.
sample=(--ignore=tests/test_notebooks.py)
if [ -z "${MECHPY_SANITIZE_ALL:-}" ]; then
    sample+=(--ignore=tests/test_plot.py --ignore=tests/test_cluster.py -m "not slow")
fi
exec "$py" -m pytest -q -p no:cacheprovider "${sample[@]}" "$@"
