"""EMPS-layout records made by an independent integrator (issue 36 Acceptance, rig records):
a closed-loop linear-motor axis following a minimum-jerk position reference, integrated by
scipy's Radau on the plain-Python model (reference/emps_record.py), written as MATLAB files
in the EMPS layout (Janot, Gautier & Brunot 2019: ``t``, ``qg``, ``qm`` in 1-µm counts,
``vir`` with 0.5-N noise) and read with ``--map``.  Mass, Coulomb and viscous friction and
the force offset are fitted from the position reference (input), the measured position and
the force (fitted); ``validate`` scores a second, held-out record of the same axis.

The two generating sets span the range of tests/unit/test_rig_record.py (which uses
feeddrive's own simulation: a round trip).  Before the position reference's rate was taken
so that its integral is the reference (``rig_record.reference_rate``), central differences
put the commanded position 0.2 µm off and these fits missed the viscous coefficient by
7.7 s.e. and the mass by 3.6 s.e.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.emps_record import emps_radau  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.fit import fit_drive  # noqa: E402
from feeddrive.analysis.rig_record import parse_map, read_rig_record, reference_rate  # noqa: E402
from feeddrive.analysis.validate import validate  # noqa: E402

DRIVE = "linear-motor"
MAP = parse_map(["time=t position=qm reference=qg force=vir"])
FREE = ["table.mass", "friction.guide.positive.coulomb_force",
        "friction.guide.positive.viscous_coefficient", "disturbances.load_force"]


def test_reference_rate_integrates_to_the_reference_and_falls_back_when_quantised() -> None:
    """The trapezoid integral of the rate is the reference at every sample (to rounding);
    a reference in 1-µm counts is refused that treatment (its alternating error would grow)
    and gets central differences."""
    t = np.arange(0.0, 1.2, 1e-3)
    tau = np.clip((t - 0.05) / 1.0, 0.0, 1.0)
    x = 0.2 * (10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5)
    v, exact = reference_rate(x, t)
    assert exact
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    assert np.max(np.abs(integral - x)) < 1e-12
    central = np.gradient(x, t)
    c_integral = np.concatenate([[0.0], np.cumsum(0.5 * (central[1:] + central[:-1])
                                                  * np.diff(t))])
    assert np.max(np.abs(c_integral - x)) > 1e-7  # what central differences leave: 0.2 µm
    q, exact_q = reference_rate(np.round(x / 1e-6) * 1e-6, t)
    assert not exact_q
    assert np.array_equal(q, np.gradient(np.round(x / 1e-6) * 1e-6, t))


@pytest.mark.slow
@pytest.mark.parametrize("mass, fc, fv, offset", [(26.0, 18.0, 80.0, 12.0),
                                                   (15.0, 11.0, 45.0, -6.0)])
def test_emps_radau_record_recovers_mass_friction_offset_and_validates(
        tmp_path: Path, mass: float, fc: float, fv: float, offset: float) -> None:
    base = fd.preset("linear-motor-example").replace_path("disturbances.load_force",
                                                          5.0 if offset > 0 else -5.0)
    truth = base
    for path, value in zip(FREE, (mass, fc, fv, offset), strict=True):
        truth = truth.replace_path(path, value)
    emps_radau(tmp_path / "estimation.mat", truth, seed=1)
    emps_radau(tmp_path / "validation.mat", truth, seed=2, stroke=0.15)
    rec = read_rig_record(tmp_path / "estimation.mat", MAP, base, drive=DRIVE)
    result = fit_drive(base, [rec.experiment], FREE, drive=DRIVE)
    assert result.inadequate is None
    for e, value in zip(result.estimates, (mass, fc, fv, offset), strict=True):
        assert e.determined, (e.path, e.issue)
        assert e.low <= value <= e.high, (e.path, e.value, e.low, e.high, value)
    fitted = tmp_path / "fitted.toml"
    fitted.write_text(result.fitted_toml("linear-motor-example"), encoding="utf-8")
    held_out = read_rig_record(tmp_path / "validation.mat", MAP, fd.load(fitted), drive=DRIVE)
    scores = {s.signal: s for s in validate(fitted, [held_out.experiment]).signals}
    # the force is predicted to its noise (0.5 N over a swing of tens of N): fit % above 90,
    # about 95 % of the samples inside the 95 % band
    assert scores["motor_current"].fit_percent > 90
    assert 0.90 <= scores["motor_current"].inside_band <= 0.99
    assert scores["table_position"].fit_percent > 99.9
