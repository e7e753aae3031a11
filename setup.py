"""Build the C core ``mechpy._core``.

GSL is found with pkg-config (or ``gsl-config``), LAPACK with pkg-config
(``lapack``, then ``openblas``).  On Debian: ``apt-get install libgsl-dev
libopenblas-dev pkg-config``.
"""
import glob
import os
import shutil
import subprocess

import numpy
from setuptools import Extension, setup


def _pkg(names, what, hint):
    for name in names:
        if shutil.which("pkg-config"):
            r = subprocess.run(["pkg-config", "--cflags", "--libs", name],
                               capture_output=True, text=True)
            if r.returncode == 0:
                return r.stdout.split()
        if name == "gsl" and shutil.which("gsl-config"):
            r = subprocess.run(["gsl-config", "--cflags", "--libs"],
                               capture_output=True, text=True)
            if r.returncode == 0:
                return r.stdout.split()
    raise SystemExit(f"mechpy: {what} not found by pkg-config; install {hint}")


def _flags():
    flags = _pkg(["gsl"], "GSL", "Debian's libgsl-dev and pkg-config")
    flags += _pkg(["lapack", "openblas"], "LAPACK",
                  "Debian's libopenblas-dev (or liblapack-dev) and pkg-config")
    inc = [f[2:] for f in flags if f.startswith("-I")]
    libdirs = [f[2:] for f in flags if f.startswith("-L")]
    libs = []
    for f in flags:
        if f.startswith("-l") and f[2:] not in libs:
            libs.append(f[2:])
    return inc, libdirs, libs


sources = sorted(glob.glob("csrc/**/*.c", recursive=True))
inc, libdirs, libs = _flags()
extra = ["-std=c11", "-O2", "-pthread", "-Wall", "-Wextra", "-Wno-missing-field-initializers",
         "-Wno-cast-function-type"]
if os.environ.get("MECHPY_SANITIZE"):
    # undefined behaviour aborts (no recovery), as does a double -> integer cast
    # out of range (not part of gcc's -fsanitize=undefined)
    extra += ["-fsanitize=address,undefined,float-cast-overflow",
              "-fno-sanitize-recover=undefined,float-cast-overflow",
              "-fno-omit-frame-pointer", "-O1", "-g"]
link_extra = ["-pthread"]
if os.environ.get("MECHPY_SANITIZE"):
    link_extra += ["-fsanitize=address,undefined,float-cast-overflow"]

setup(
    ext_modules=[
        Extension(
            "mechpy._core",
            sources=sources,
            include_dirs=["csrc", numpy.get_include()] + inc,
            library_dirs=libdirs,
            libraries=libs,
            extra_compile_args=extra,
            extra_link_args=link_extra,
            define_macros=[("NPY_NO_DEPRECATED_API", "NPY_1_7_API_VERSION")],
        )
    ]
)
