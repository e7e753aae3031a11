#!/usr/bin/env bash
# Set up mechpy on this machine (once) and run one of its jobs.
#
#   bash scripts/dev.sh tour     # set up, then: python -m mechpy tour
#   bash scripts/dev.sh test     # set up, then: the test suite, then the suite again
#                                #   against the ASan+UBSan build (scripts/sanitize.sh)
#   bash scripts/dev.sh bench    # set up (with the bench extras), then: python -m mechpy bench
#
# Set-up installs what is missing and nothing twice: Debian's libgsl-dev,
# libopenblas-dev and pkg-config (apt-get, as root or through sudo), a virtual
# environment in .venv, and mechpy in it (editable) with its extras.  The
# package is rebuilt only when its C sources or build files change.
set -euo pipefail
cd "$(dirname "$0")/.."
job=${1:-test}
shift || true

say() { printf 'mechpy setup: %s\n' "$*"; }

# 1. System libraries -------------------------------------------------------
debs=(libgsl-dev libopenblas-dev pkg-config)
# the bench compares with numbalsoda, built from source with a Fortran compiler
[ "$job" = bench ] && debs+=(gfortran)
missing=()
if command -v dpkg-query >/dev/null 2>&1; then
    for p in "${debs[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
    done
elif ! pkg-config --exists gsl 2>/dev/null; then
    say "GSL not found and this is not a Debian system: install GSL (>= 2.5), LAPACK and pkg-config"
    exit 1
fi
if [ ${#missing[@]} -gt 0 ]; then
    say "installing Debian packages: ${missing[*]}"
    if [ "$(id -u)" = 0 ]; then sudo=""; elif command -v sudo >/dev/null; then sudo="sudo"; else
        say "cannot install ${missing[*]}: run 'apt-get install ${missing[*]}' as root"; exit 1; fi
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq || { say "apt-get update failed; install ${missing[*]} by hand"; exit 1; }
    $sudo apt-get install -y -qq "${missing[@]}" >/dev/null ||
        { say "apt-get could not install ${missing[*]}"; exit 1; }
fi

# 2. Virtual environment ----------------------------------------------------
py=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    say "creating .venv"
    "$py" -m venv .venv
fi
vpy=.venv/bin/python

# 3. The package, rebuilt only when sources or build files change ------------
extras="test"
[ "$job" = bench ] && extras="test,bench"
stamp=$( (cat pyproject.toml setup.py; find csrc -type f -name '*.[ch]' | sort | xargs cat; echo "$extras ${MECHPY_SANITIZE:-}") | sha256sum | cut -c1-16)
if [ "$(cat .venv/.mechpy-stamp 2>/dev/null)" != "$stamp" ]; then
    say "installing mechpy[$extras] into .venv"
    "$vpy" -m pip install -q --upgrade pip >/dev/null
    "$vpy" -m pip install -q "setuptools>=64" wheel "numpy>=2.0"
    # numbalsoda (bench extra) is built from source with its own build tools:
    # install it with build isolation before mechpy's isolation-free install
    [ "$job" = bench ] && "$vpy" -m pip install -q numbalsoda
    "$vpy" -m pip install -q --no-build-isolation -e ".[$extras]"
    echo "$stamp" > .venv/.mechpy-stamp
fi

# 3b. The docs job ------------------------------------------------------------
#   bash scripts/dev.sh docs     # set up (with the docs extra), then: the site, built with
#                                #   warnings as errors, into docs/_build/html (index.html)
if [ "$job" = docs ]; then
    # formulas render offline with Debian's MathJax, when it can be installed
    if command -v dpkg-query >/dev/null 2>&1 &&
       ! dpkg-query -W -f='${Status}' libjs-mathjax 2>/dev/null | grep -q 'install ok installed'; then
        if [ "$(id -u)" = 0 ]; then sudo=""; else sudo="sudo"; fi
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
    "$vpy" -m sphinx -W --keep-going -b html docs docs/_build/html "$@"
    say "the site is in docs/_build/html/index.html"
    exit 0
fi

# 4. The job -----------------------------------------------------------------
case "$job" in
    tour)  exec "$vpy" -m mechpy tour "$@" ;;
    bench) exec "$vpy" -m mechpy bench "$@" ;;
    test)  # the suite, then the same suite against the ASan+UBSan build
           # (scripts/sanitize.sh; MECHPY_SANITIZE_SKIP=1 skips that second pass)
           "$vpy" -m pytest -q "$@"
           [ -n "${MECHPY_SANITIZE_SKIP:-}" ] && exit 0
           say "the test suite again, under AddressSanitizer and UndefinedBehaviorSanitizer"
           PYTHON="$vpy" exec bash scripts/sanitize.sh "$@" ;;
    *) say "unknown job '$job' (tour, test or bench)"; exit 2 ;;
esac
