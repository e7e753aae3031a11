"""Command line: ``python -m mechpy tour`` and ``python -m mechpy bench``."""
import argparse
import sys
from pathlib import Path


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m mechpy")
    sub = p.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser("tour", help="run every scene; print results, errors and times")
    t.add_argument("--out", type=Path, default=Path("mechpy-output"), help="folder for figures")
    b = sub.add_parser("bench", help="work-precision report, mechpy beside SciPy")
    b.add_argument("--quick", action="store_true", help="a short run (under a minute)")
    b.add_argument("--out", type=Path, default=Path("bench-output"), help="output folder")
    a = p.parse_args(argv)
    if a.cmd == "tour":
        from .tours import run_all
        return 1 if run_all(a.out) else 0
    from .bench import main as bench_main
    return bench_main(quick=a.quick, out=a.out)


if __name__ == "__main__":
    sys.exit(main())
