"""Rig records in the EMPS layout (Janot, Gautier & Brunot 2019: ``t``, position reference
``qg``, measured position ``qm``, motor force ``vir``; a closed-loop axis), made by an
integrator other than feeddrive's: the plain-Python model (:mod:`reference.scipy_model`,
linear-motor drive) integrated by scipy's Radau, then measured as a rig would (position in
encoder counts, force with white noise, both seeded), for the acceptance of issue 36's rig
records and held-out validation.  ``feeddrive.analysis.rig_record.emps_layout`` writes the
same layout from feeddrive's own simulation (a round trip, not a calibration).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from feeddrive.parameters import DriveParameters  # noqa: E402
from reference.make_radau_reference import radau_states  # noqa: E402
from reference.scipy_model import ReferenceModel  # noqa: E402

MOVE_START = 0.05  # [s]
MOVE_TIME = 1.0  # [s]


@dataclass(frozen=True)
class MinimumJerk:
    """Position reference 0 → ``stroke`` [m], x = s·(10τ³ − 15τ⁴ + 6τ⁵), τ = (t − start)/T
    clipped to [0, 1] (Flash & Hogan 1985), and its exact rate, as the reference model's
    ``signals(t)`` = (x_ref, v_ref, 0, 0) [m, m/s]."""

    stroke: float
    start: float = MOVE_START
    move_time: float = MOVE_TIME

    def position(self, t: np.ndarray | float) -> np.ndarray:
        tau = np.clip((np.asarray(t, dtype=float) - self.start) / self.move_time, 0.0, 1.0)
        return self.stroke * (10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5)

    def signals(self, t: float) -> tuple[float, float, float, float]:
        tau = min(max((t - self.start) / self.move_time, 0.0), 1.0)
        x = self.stroke * (10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5)
        v = self.stroke * (30 * tau ** 2 - 60 * tau ** 3 + 30 * tau ** 4) / self.move_time
        return x, v, 0.0, 0.0


def emps_radau(path: str | Path, truth: DriveParameters, *, seed: int = 0,
               duration: float = 1.6, stroke: float = 0.2, offset: float = 0.01,
               force_noise: float = 0.5, encoder: float = 1e-6) -> Path:
    """Write a ``.mat`` (v5) record of the linear-motor axis ``truth`` following a
    minimum-jerk move of ``stroke`` [m] from 0.05 s over 1 s, ``duration`` [s] at 1 kHz:
    ``qg`` the position reference, ``qm`` the table position in ``encoder`` counts [m],
    both shifted by ``offset`` [m], ``vir`` the motor force K_f·i [N] with white noise of
    σ ``force_noise`` [N] (seeded); column vectors as MATLAB writes them."""
    import scipy.io as sio

    move = MinimumJerk(stroke)
    t, y, _ = radau_states(truth, "linear-motor", move, duration, 1e-9, 1e-2)
    names = ReferenceModel(truth, "linear-motor", 0.4, move).state_names
    lm = truth.linear_motor
    assert lm is not None
    rng = np.random.default_rng(seed)
    qm = np.round(y[names.index("table_position")] / encoder) * encoder
    vir = lm.force_constant * y[names.index("motor_current")] \
        + force_noise * rng.standard_normal(t.size)
    out = Path(path)
    sio.savemat(out, {"t": t[:, None], "qg": (move.position(t) + offset)[:, None],
                      "qm": (qm + offset)[:, None], "vir": vir[:, None]})
    return out
