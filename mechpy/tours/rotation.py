"""Tour section: Euler angles (section 5 of the notes), a round trip and speed."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

TITLE = "Rotations: Euler angles, gimbal lock, omega from the rates"
ORDER = 50


def run(out: Path) -> None:
    from scipy.spatial.transform import Rotation

    from .. import rotation as rot
    from ..benches.rotation import measure
    from . import line

    phi, theta, psi = 0.3, 1.1, -0.7
    L = rot.euler_matrix(phi, theta, psi)
    ref = Rotation.from_euler("ZXZ", [phi, theta, psi]).as_matrix().T
    line("lambda = lambda_psi lambda_theta lambda_phi", "(3, 3)",
         ref="Rotation.from_euler('ZXZ').as_matrix().T", err=float(np.max(np.abs(L - ref))))

    # round trip angles -> matrix -> angles -> matrix, all 24 sequences, with locks
    rng = np.random.default_rng(1)
    worst = 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rot.GimbalLockWarning)
        for seq in rot.SEQUENCES:
            a = rng.uniform(-np.pi, np.pi, (20_000, 3))
            if seq[0].lower() == seq[2].lower():
                lock = [0.0, np.pi, 1e-9, np.pi - 1e-9]
            else:
                lock = [np.pi / 2, -np.pi / 2, np.pi / 2 - 1e-9, -np.pi / 2 + 1e-9]
            a[:4000, 1] = np.repeat(lock, 1000)
            for passive in (True, False):
                R1 = rot.euler_matrix(a, seq=seq, passive=passive)
                R2 = rot.euler_matrix(rot.euler_angles(R1, seq, passive), seq=seq,
                                      passive=passive)
                worst = max(worst, float(np.max(np.abs(R2 - R1))))
    line("round trip, 24 seqs, both kinds, with locks", "max |R2 - R1|", err=worst)

    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        a = rot.euler_angles(rot.euler_matrix(0.4, 0.0, 0.3))
    line("gimbal lock theta = 0: (phi, theta, psi)", np.array2string(a, precision=3),
         ref="(0.7, 0, 0)", err=float(np.max(np.abs(a - [0.7, 0, 0]))))
    print(f"  {'':44s} warnings issued: {len(w)} ({w[0].category.__name__})")

    rates = np.array([0.5, -0.2, 2.0])
    w_body = rot.angular_velocity([phi, theta, psi], rates)
    text = np.array([rates[0] * np.sin(theta) * np.sin(psi) + rates[1] * np.cos(psi),
                     rates[0] * np.sin(theta) * np.cos(psi) - rates[1] * np.sin(psi),
                     rates[0] * np.cos(theta) + rates[2]])
    line("omega (body) from Euler rates", np.array2string(w_body, precision=4),
         ref="textbook omega_1..3", err=float(np.max(np.abs(w_body - text))))

    for m in measure(100_000, repeat=3):   # python -m mechpy bench: 10^6
        line(f"10^5 {m['problem']}", "", err=m["error"], t_mp=m["t_mp"], t_ref=m["t_sp"])
