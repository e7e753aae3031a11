#!/usr/bin/env bash
# Set up mechpy on this machine (once) and run one of its jobs.
#
#   bash scripts/dev.sh tour     # set up, then: python -m mechpy tour
#   bash scripts/dev.sh test     # set up, then: the test suite once, against mechpy built
#                                #   from its sdist and installed into a fresh environment
#                                #   (the editable install when the work tree has changes not
#                                #   yet committed), and beside it (the other core) the suite
#                                #   against the ASan+UBSan build (scripts/sanitize.sh); each
#                                #   pass's output in build/ci/, printed when both are done,
#                                #   with its 15 slowest tests
#   bash scripts/dev.sh bench    # set up (with the bench extras), then: python -m mechpy bench
#
# Set-up installs what is missing and nothing twice: Debian's libgsl-dev,
# libopenblas-dev and pkg-config (apt-get, as root or through sudo; without
# either, or off Debian, none: GSL is then built from subprojects/gsl.wrap and
# LAPACK comes from the scipy-openblas32 wheel, and the script says so), a virtual
# environment in .venv, and mechpy in it as an editable meson-python install
# (build directory build/editable) with its extras.  The editable install
# rebuilds the C core on import whenever csrc/ changes (in every interpreter
# of .venv: tests, their subprocesses, notebook kernels); pip runs again only
# when the build files or the extras change.
#
# MECHPY_SANITIZE_SKIP=1 skips the sanitizer pass; MECHPY_SDIST_SKIP=1 runs the suite
# against the editable install in .venv instead of the sdist-installed copy.
set -euo pipefail
cd "$(dirname "$0")/.."
job=${1:-test}
shift || true

say() { printf 'mechpy setup: %s\n' "$*"; }

# 1. System libraries -------------------------------------------------------
debs=(libgsl-dev libopenblas-dev pkg-config)
# the bench compares with numbalsoda, built from source with a Fortran compiler, and with
# CVODE through SUNDIALS' C API (mechpy/benches/stiff_cvode.py compiles its driver)
[ "$job" = bench ] && debs+=(gfortran libsundials-dev)
# the live views' tests and their bench run in headless Chromium (software WebGL2)
case "$job" in test|bench|docs) debs+=(chromium chromium-driver) ;; esac
missing=()
if command -v dpkg-query >/dev/null 2>&1; then
    for p in "${debs[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
    done
fi
# Without root (and no sudo), or off Debian: no apt-get; the build takes what pkg-config
# finds, else GSL from subprojects/gsl.wrap (built into mechpy) and LAPACK from the
# scipy-openblas32 wheel (meson.build); tests that need Chromium skip without it.
if [ "$(id -u)" = 0 ]; then sudo=""
elif command -v sudo >/dev/null 2>&1 && { [ -t 0 ] || sudo -n true 2>/dev/null; }; then
    sudo="sudo"   # (asks for a password at a terminal)
else sudo="none"; fi
if ! command -v dpkg-query >/dev/null 2>&1 || [ "$sudo" = none ]; then
    why="not a Debian system"; command -v dpkg-query >/dev/null 2>&1 && why="no root and no sudo"
    if pkg-config --exists gsl 2>/dev/null; then gsl_from="the system's GSL (pkg-config)"
    else gsl_from="GSL 2.7.1 built from subprojects/gsl.wrap (source from deb.debian.org)"; fi
    if pkg-config --exists lapack 2>/dev/null || pkg-config --exists openblas 2>/dev/null; then
        lapack_from="the system's LAPACK (pkg-config)"
    else lapack_from="OpenBLAS from the scipy-openblas32 wheel (PyPI)"; fi
    [ ${#missing[@]} -gt 0 ] && say "$why: not installing ${missing[*]} (apt-get)"
    say "$why: using $gsl_from and $lapack_from"
    missing=()
fi
if [ ${#missing[@]} -gt 0 ]; then
    say "installing Debian packages: ${missing[*]}"
    [ "$sudo" = "" ] || say "(through sudo)"
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq || { say "apt-get update failed; install ${missing[*]} by hand"; exit 1; }
    $sudo apt-get install -y -qq "${missing[@]}" >/dev/null ||
        { say "apt-get could not install ${missing[*]}"; exit 1; }
fi

# MECHPY_SETUP_SYSTEM_ONLY=1: this step alone (tests/test_install.py checks what it says)
[ -n "${MECHPY_SETUP_SYSTEM_ONLY:-}" ] && exit 0

# 2. Virtual environment ----------------------------------------------------
py=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    say "creating .venv"
    "$py" -m venv .venv
fi
vpy=.venv/bin/python

# 3. The package: an editable install, pip run only when build files change --
extras="test"
[ "$job" = bench ] && extras="test,bench"
buildfiles() { cat pyproject.toml; find . -name meson.build -not -path './.venv/*' -not -path './build/*' -not -path './subprojects/gsl/*' | sort | xargs cat; }
stamp=$( (buildfiles; echo "$extras") | sha256sum | cut -c1-16)
if [ "$(cat .venv/.mechpy-stamp 2>/dev/null)" != "$stamp" ] || [ ! -f build/editable/build.ninja ]; then
    say "installing mechpy[$extras] into .venv (editable, built in build/editable)"
    "$vpy" -m pip install -q --upgrade pip >/dev/null
    # the build tools in .venv itself: the editable install rebuilds with them on import.
    # setuptools >= 70.1 (bdist_wheel built in): the install below runs without build
    # isolation, so an extra published only as an sdist (pydy) is built with the venv's own
    # setuptools, and the one a fresh venv carries (65.x, no wheel package) cannot
    "$vpy" -m pip install -q "meson-python>=0.18" "meson>=1.1" ninja "numpy>=2.0" \
        "scipy-openblas32>=0.3.27" "setuptools>=70.1"
    # the distribution was called mechpy before it was mechpy-classical: one editable
    # install of the package, not two
    "$vpy" -m pip uninstall -q -y mechpy >/dev/null 2>&1 || true
    # numbalsoda (bench extra) is built from source with its own build tools:
    # install it with build isolation before mechpy's isolation-free install
    [ "$job" = bench ] && "$vpy" -m pip install -q numbalsoda
    "$vpy" -m pip install -q --no-build-isolation -Cbuild-dir="$PWD/build/editable" -e ".[$extras]"
    echo "$stamp" > .venv/.mechpy-stamp
fi
# build now (not at the first import, inside a timed test)
"$vpy" -c "import mechpy" || { say "mechpy does not import from .venv"; exit 1; }

# The sdist pass: build the sdist, install it (with build isolation) into a
# fresh environment, run the suite against that copy from a folder where the
# source tree is not importable.  Redone only when the committed tree changes
# (the sdist holds what git tracks at HEAD).
sdist_pass() {
    local out=build/sdist env=build/sdist/venv
    local st; st=$(printf '%s %s' "$(git rev-parse 'HEAD^{tree}')" "$("$vpy" -c 'import sys; print(sys.version)')" | sha256sum | cut -c1-16)
    if [ "$(cat "$out/.stamp" 2>/dev/null)" != "$st" ] || [ ! -x "$env/bin/python" ]; then
        say "building the sdist and installing it into a fresh environment ($env)"
        rm -rf "$out"; mkdir -p "$out"
        "$vpy" -m pip install -q build
        "$vpy" -m build --sdist --outdir "$out" . >"$out/build.log" 2>&1 ||
            { tail -30 "$out/build.log"; say "python -m build --sdist failed"; return 1; }
        local sd; sd=$(ls "$out"/mechpy_classical-*.tar.gz)
        # the files the build needs are in the sdist (it holds what git tracks)
        local listing; listing=$(tar -tzf "$sd")
        for f in LICENSE meson.build csrc/meson.build csrc/check_sources.py mechpy/py.typed; do
            grep -qx "mechpy_classical-[^/]*/$f" <<<"$listing" || { say "$f is missing from $sd"; return 1; }
        done
        "$vpy" -m venv "$env"
        "$env/bin/python" -m pip install -q --upgrade pip >/dev/null
        "$env/bin/python" -m pip install -q "$sd[test]" ||
            { say "installing $sd (with build isolation) failed"; return 1; }
        echo "$st" > "$out/.stamp"
    fi
    # the tests and notebooks in a folder of their own (no mechpy/ beside them), with
    # pyproject.toml (pytest's settings), README.md and csrc/ (the tests that check the
    # README's Layout read them); notebook kernels start from this environment's python,
    # so they import the same copy
    local run=$out/run
    rm -rf "$run"; mkdir -p "$run"
    cp -r tests notebooks README.md pyproject.toml csrc "$run/"
    find "$run" -name __pycache__ -prune -exec rm -rf {} +
    say "the test suite against mechpy installed from $(basename "$(ls "$out"/mechpy_classical-*.tar.gz)")"
    # MECHPY_SOURCE_DIR: the checkout, for the test that builds a clone of it
    (cd "$run" && PYTHONSAFEPATH=1 MECHPY_INSTALLED_COPY=1 MECHPY_SOURCE_DIR="$OLDPWD" \
        "$OLDPWD/$env/bin/python" -m pytest -q \
        -p no:cacheprovider --rootdir=. "$@")
}

# The suite runs once: against the sdist-installed copy when the work tree is a clean git
# checkout (as CI's fresh clone is: the sdist holds HEAD), else against the editable install.
suite() {
    local why=""
    if [ -n "${MECHPY_SDIST_SKIP:-}" ]; then why="MECHPY_SDIST_SKIP is set"
    elif ! git rev-parse -q --verify HEAD >/dev/null 2>&1; then why="not a git checkout"
    elif [ -n "$(git status --porcelain 2>/dev/null)" ]; then
        why="the work tree has changes not committed (the sdist holds HEAD)"
    fi
    if [ -z "$why" ]; then sdist_pass "$@"; return; fi
    say "the test suite against the editable install in .venv ($why)"
    "$vpy" -m pytest -q "$@"
}

# 3b. The docs job ------------------------------------------------------------
#   bash scripts/dev.sh docs     # set up (with the docs extra), then: the site, built with
#                                #   warnings as errors, into docs/_build/html (index.html)
if [ "$job" = docs ]; then
    # formulas render offline with Debian's MathJax, when it can be installed
    if command -v dpkg-query >/dev/null 2>&1 &&
       ! dpkg-query -W -f='${Status}' libjs-mathjax 2>/dev/null | grep -q 'install ok installed'; then
        if [ "$sudo" = none ]; then sudo="false"; fi
        say "installing Debian's libjs-mathjax (formulas without a network)"
        DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq libjs-mathjax >/dev/null 2>&1 ||
            say "libjs-mathjax not installed: the site loads MathJax from its CDN"
    fi
    reqs=$(sed -n '/^docs = \[/,/^\]/p' pyproject.toml | grep -o '"[^"]*"' | tr -d '"')
    dstamp=$(printf '%s\n' "$reqs" | sha256sum | cut -c1-16)
    if [ "$(cat .venv/.mechpy-docs-stamp 2>/dev/null)" != "$dstamp" ]; then
        say "installing the docs extra into .venv"
        # shellcheck disable=SC2086  # one requirement a word
        "$vpy" -m pip install -q $reqs
        echo "$dstamp" > .venv/.mechpy-docs-stamp
    fi
    "$vpy" -m sphinx -W --keep-going -b html -d docs/_build/doctrees docs docs/_build/html "$@"
    say "the site is in docs/_build/html/index.html"
    exit 0
fi

# 4. The job -----------------------------------------------------------------
case "$job" in
    tour)  exec "$vpy" -m mechpy tour "$@" ;;
    bench) exec "$vpy" -m mechpy bench "$@" ;;
    test)  # the suite once (sdist-installed or editable) and under the sanitizers, side
           # by side (one core each); each pass's output is kept and printed after both
           # end; either failing fails the run, with the first failure's status
           if [ -n "${MECHPY_SANITIZE_SKIP:-}" ]; then
               t0=$SECONDS
               suite --durations=15 "$@"
               say "the suite took $((SECONDS - t0)) s (with its set-up)"
               exit 0
           fi
           logs=build/ci; mkdir -p "$logs"
           t0=$SECONDS
           say "the test suite and, beside it, the suite under AddressSanitizer and" \
               "UndefinedBehaviorSanitizer (outputs in $logs/suite.log, $logs/sanitize.log)"
           # each pass in a subshell of its own (errexit applies inside it as in a plain run)
           ( suite --durations=15 "$@" ) >"$logs/suite.log" 2>&1 &
           p1=$!
           ( PYTHON="$vpy" bash scripts/sanitize.sh --durations=15 "$@" ) >"$logs/sanitize.log" 2>&1 &
           p2=$!
           # whichever ends first is printed first; the run's status is the first failure's
           rc=0; first=""; left=("$p1" "$p2")
           while [ ${#left[@]} -gt 0 ]; do
               r=0; fin=""; wait -n -p fin "${left[@]}" || r=$?
               if [ -z "$fin" ]; then say "lost track of the passes (wait: $r)"; rc=1; break; fi
               if [ "$fin" = "$p1" ]; then name=suite; what="the suite (with its set-up)"
               else name=sanitize; what="the sanitizer pass (with its build)"; fi
               rest=(); for p in "${left[@]}"; do [ "$p" = "$fin" ] || rest+=("$p"); done
               left=("${rest[@]}")
               printf '\n==== %s (%s) ====\n' "$what" "$logs/$name.log"
               cat "$logs/$name.log"
               say "$what took $((SECONDS - t0)) s, exit status $r"
               if [ "$r" -ne 0 ] && [ "$rc" -eq 0 ]; then rc=$r; first=$what; fi
           done
           say "both passes took $((SECONDS - t0)) s side by side"
           [ "$rc" -eq 0 ] || say "FAILED: $first (exit status $rc)"
           exit "$rc" ;;
    *) say "unknown job '$job' (tour, test or bench)"; exit 2 ;;
esac
