#!/usr/bin/env bash
# Run the test suite against mechpy's C core built with AddressSanitizer and
# UndefinedBehaviorSanitizer (any report fails the run).
#
#   bash scripts/sanitize.sh [pytest args]      # PYTHON=... to choose the interpreter
#
# The sanitized extension is built into build/asan/ (a copy of the package with
# its own mechpy/_core*.so), rebuilt only when the C sources or build files
# change; the normal (editable) build is not touched.  Python is not sanitized,
# so gcc's libasan is preloaded.  Leaks: LeakSanitizer runs at the end of the
# session inside the live interpreter (tests/conftest.py), where everything
# Python still holds is reachable, so only blocks nobody points to any more
# are reported; the exit-time check (interpreter teardown noise) is off.
set -euo pipefail
cd "$(dirname "$0")/.."
py=${PYTHON:-python3}
out=build/asan
say() { printf 'mechpy sanitize: %s\n' "$*"; }

stamp=$( (cat setup.py pyproject.toml; find csrc -type f -name '*.[ch]' | sort | xargs cat) | sha256sum | cut -c1-16)
if [ "$(cat "$out/.stamp" 2>/dev/null)" != "$stamp" ] || ! ls "$out"/mechpy/_core*.so >/dev/null 2>&1; then
    say "building the ASan+UBSan extension into $out"
    rm -rf "$out"
    mkdir -p "$out"
    MECHPY_SANITIZE=1 "$py" setup.py -q build_ext --build-lib "$out" --build-temp "$out/tmp" \
        2>&1 | { grep -E 'warning|error' || true; }
    ls "$out"/mechpy/_core*.so >/dev/null
    echo "$stamp" > "$out/.stamp"
fi
# the Python sources are copied every run (cheap), next to the sanitized .so
find "$out/mechpy" -name '*.py' -delete
(cd mechpy && find . -name '*.py' -not -path '*/__pycache__/*' -print0 |
    xargs -0 -I{} install -D -m 644 {} "../$out/mechpy/{}")

libasan=$(gcc -print-file-name=libasan.so)
[ -e "$libasan" ] || { say "gcc's libasan.so not found (Debian: apt-get install gcc)"; exit 1; }
# libstdc++ too: loaded before ASan initialises, its __cxa_throw interceptor works
# (C++ extensions such as matplotlib's ft2font throw during import).
libstdcxx=$(gcc -print-file-name=libstdc++.so)
export LD_PRELOAD="$libasan${libstdcxx:+ $libstdcxx}"
export ASAN_OPTIONS="detect_leaks=1:leak_check_at_exit=0:abort_on_error=1:halt_on_error=1:detect_stack_use_after_return=0:allocator_may_return_null=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
export PYTHONMALLOC=malloc          # every allocation visible to ASan/LSan
export PYTHONPATH="$PWD/$out${PYTHONPATH:+:$PYTHONPATH}"
export PYTHONSAFEPATH=1           # no cwd on sys.path: the copy in build/asan is imported
export MECHPY_SANITIZED=1
# The notebooks run in Jupyter kernels (a third interpreter each, slow under ASan)
# and call the same C paths as the tests: they run in the normal pass only.
exec "$py" -m pytest -q -p no:cacheprovider --ignore=tests/test_notebooks.py "$@"
