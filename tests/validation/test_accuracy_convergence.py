"""Issue 35 item 2: the error of every method falls with ``accuracy``, on references feeddrive
did not make.

Frictionless velocity steps (``wang2021-literal`` with the friction of every site off, table
basis, axial damping 2000 N s/m, K_eq frozen at mid-screw, no start ramp): the closed loop is
linear, and its exact response is the matrix exponential of the augmented matrix written out by
hand from the equations in ``reference/linear_model.py`` (not from feeddrive's model).  CDFS and
DDFS (hollow motor at 16 mm/s, Wang2021 Fig. 8) at 0.1, 1 and 10 mm/s, 1 s (the table mode's
ringing, where the error is largest, is over by then).

For each method the largest table-speed error relative to the peak table speed, at
``accuracy`` 1, 0.1, 0.01, 0.001:

* every decade lowers it at least 5× (or it is already below 1e-12 of the peak);
* the dense-output methods (``modal``, ``auto``, ``rodas4``, ``dopri5-dense``) are within
  1e-5 of the peak at the defaults and within 1e-8 at ``accuracy = 0.001`` (the issue's
  acceptance).

``dopri5`` lands on every output instant, so its steps are capped by the output interval; its
convergence is checked with a 10-ms output (at 1 ms its first decade is 4.4–4.9×, measured
2026-12-04 with the fixed 1-ms cap, and 4.4–6.4× with the cap at 1 ms × accuracy^(1/5),
2026-12-05; at 0.1 ms it sits at 2.3e-10 of the peak at every accuracy, measured 2026-12-04).
"""

from __future__ import annotations

import sys
from functools import cache
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.linear_model import augmented_matrix, exact_response  # noqa: E402
from reference.scipy_model import STATE_NAMES  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.engine.simulate import DriveSystem, SolverOptions, simulate  # noqa: E402
from feeddrive.model.mechanisms.ball_screw_stiffness import equivalent_stiffness  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402

ACCURACIES = (1.0, 0.1, 0.01, 0.001)
DENSE = ("modal", "auto", "rodas4", "dopri5-dense")
CASES = [(drive, v) for drive in ("cdfs", "ddfs") for v in (1e-4, 1e-3, 1e-2)]
DURATION = 1.0
NUT_SPEED = 16e-3  # [m/s] the DDFS hollow motor (Wang2021 Fig. 8)
TABLE_SPEED = STATE_NAMES.index("table_speed")


@cache
def frictionless() -> fd.DriveParameters:
    p = (fd.preset("wang2021-literal").replace_path("stiffness.axial_damping", 2000.0)
         .replace_path("stiffness.position_dependent", False)
         .replace_path("controller.velocity_gain_basis", "table"))
    for site in ("screw", "nut", "guide"):
        p = p.replace_path(f"friction.{site}.law", "none")
    return p


def errors(method: str, drive: str, speed: float) -> list[float]:
    """The largest table-speed error over the peak table speed, per accuracy."""
    params = frictionless()
    nut = NUT_SPEED if drive == "ddfs" else 0.0
    profile = ConstantSpeed(table_speed=speed, nut_speed=nut, ramp_time=0.0)
    A = augmented_matrix(params, drive, speed, nut, equivalent_stiffness(params, 0.4))
    out = []
    for acc in ACCURACIES:
        options = SolverOptions(method=method, accuracy=acc,
                                output_interval=1e-2 if method == "dopri5" else 1e-3)
        r = simulate(DriveSystem(params, drive, 0.4), profile, DURATION, options=options)
        exact = exact_response(A, r.time)[:, TABLE_SPEED]
        out.append(float(np.max(np.abs(r["table_speed"] - exact)) / np.max(np.abs(exact))))
    return out


def assert_converges(errs: list[float], floor: float = 1e-12) -> None:
    """Each decade of accuracy lowers the error 5× at least, unless it is at ``floor`` (of
    the peak table speed) already."""
    for a, b in zip(errs, errs[1:], strict=False):
        assert b <= a / 5.0 or b <= floor, errs


@pytest.mark.slow
@pytest.mark.parametrize(("drive", "speed"), CASES)
@pytest.mark.parametrize("method", [*DENSE, "dopri5"])
def test_every_method_converges_with_accuracy(method: str, drive: str, speed: float) -> None:
    errs = errors(method, drive, speed)
    # double precision's floor: 1e-12 of the signal's range.  A DDFS's table speed is the
    # difference of the motors' motions (angles of the screw's travel at v + v_n): its
    # states resolve it to about 1e-12 of the motors' speed, not of the table's own (at
    # 0.1 mm/s between motors at 16 mm/s: rodas4 4.4e-10 -> 9.9e-11 -> 5.6e-11 at accuracy
    # 1e-2, 1e-3, 1e-4, of the table's peak; measured 2026-12-04)
    nut = NUT_SPEED if drive == "ddfs" else 0.0
    assert_converges(errs, floor=1e-12 * (speed + nut) / speed)
    if method in DENSE:
        assert errs[0] <= 1e-5, errs  # the defaults
        assert errs[-1] <= 1e-8, errs  # accuracy = 0.001


def test_the_rule_fails_a_method_that_stalls() -> None:
    # the check itself can fail: an error that stops falling is caught
    with pytest.raises(AssertionError):
        assert_converges([1e-6, 1e-7, 5e-8, 1e-9])
    assert_converges([1e-6, 1e-7, 1e-8, 1e-13])
