"""Rotation conversions on a batch of 10^6: mechpy beside SciPy's ``Rotation``.

Each problem is one conversion (Euler angles to matrix, matrix to Euler
angles, Euler to quaternion, quaternion to matrix, matrix to quaternion,
quaternion to Euler), timed on the same random input for mechpy and SciPy
in one run; ``error`` is the largest difference from SciPy's result
(angles compared modulo 2 pi).
"""
from __future__ import annotations

import warnings

import numpy as np

TITLE = "Rotations: 10^6 conversions beside scipy.spatial.transform.Rotation"
ORDER = 50

SEQ = "ZXZ"


def _angle_err(a, b):
    return float(np.max(np.abs(np.angle(np.exp(1j * (a - b))))))


def cases(n: int, seed: int = 0):
    """(problem, mechpy callable, scipy callable, error function) for n rotations."""
    from scipy.spatial.transform import Rotation

    from .. import rotation as rot

    rng = np.random.default_rng(seed)
    ang = rng.uniform(-np.pi, np.pi, (n, 3))
    ang[:, 1] = rng.uniform(0.0, np.pi, n)
    R = Rotation.from_euler(SEQ, ang).as_matrix()
    q = Rotation.from_euler(SEQ, ang).as_quat()
    mat_err = lambda a, b: float(np.max(np.abs(a - b)))  # noqa: E731
    return [
        ("euler -> matrix", lambda: rot.euler_matrix(ang, seq=SEQ, passive=False),
         lambda: Rotation.from_euler(SEQ, ang).as_matrix(), mat_err),
        ("matrix -> euler", lambda: rot.euler_angles(R, SEQ, passive=False),
         lambda: Rotation.from_matrix(R).as_euler(SEQ), _angle_err),
        ("euler -> quat", lambda: rot.quat_from_euler(ang, seq=SEQ, passive=False),
         lambda: Rotation.from_euler(SEQ, ang).as_quat(), mat_err),
        ("quat -> euler", lambda: rot.euler_from_quat(q, SEQ, passive=False),
         lambda: Rotation.from_quat(q).as_euler(SEQ), _angle_err),
        ("matrix -> quat", lambda: rot.quat_from_matrix(R),
         lambda: Rotation.from_matrix(R).as_quat(), mat_err),
        ("quat -> matrix", lambda: rot.matrix_from_quat(q),
         lambda: Rotation.from_quat(q).as_matrix(), mat_err),
    ]


def measure(n: int, repeat: int = 3):
    """One dict per conversion: times of both, their ratio, and the difference."""
    from .._timing import median_time
    out = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)   # rare random gimbal locks
        for name, f_mp, f_sp, err in cases(n):
            t_mp = median_time(f_mp, repeat=repeat)
            t_sp = median_time(f_sp, repeat=repeat)
            out.append({"problem": name, "t_mp": t_mp, "t_sp": t_sp,
                        "error": err(f_mp(), f_sp())})
    return out


def run(quick: bool) -> list[dict]:
    n = 100_000 if quick else 1_000_000
    rows = []
    for m in measure(n, repeat=3 if quick else 5):
        prob = f"rotation {m['problem']} ({SEQ}, n={n:.0e})"
        rows.append({"problem": prob, "impl": "mechpy (C loop)", "time": m["t_mp"],
                     "error": m["error"], "n": n, "ratio": m["t_sp"] / m["t_mp"],
                     "note": f"{m['t_sp'] / m['t_mp']:.1f}x SciPy's speed; error = max diff "
                             "from SciPy"})
        rows.append({"problem": prob, "impl": "scipy Rotation", "time": m["t_sp"],
                     "error": float("nan"), "n": n, "note": "reference"})
    return rows
