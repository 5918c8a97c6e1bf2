"""Real rig records for `feeddrive fit` (issue 36 item 5): MATLAB files with the variables
mapped to roles, in the EMPS benchmark's layout (Janot, Gautier & Brunot 2019: ``t``, ``qg``
position reference, ``qm`` measured position, ``vir`` motor force), made here by our own
generator (no download).

The generator simulates the linear-motor drive with feeddrive itself: these tests check the
reader, the position reference as the input and the force as a fitted signal end to end (a
round trip), not the intervals' calibration, which needs traces from an independent
integrator (docs/fitting.md, "Calibration").
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io as sio

import feeddrive as fd
from feeddrive.analysis import rig_record as rr
from feeddrive.analysis.fit import FitError, fit_drive
from feeddrive.analysis.rig_record import emps_layout, parse_map, read_rig_record

DRIVE = "linear-motor"
MAP = ["time=t position=qm reference=qg force=vir"]
FREE = ["table.mass", "friction.guide.positive.coulomb_force",
        "friction.guide.positive.viscous_coefficient", "disturbances.load_force"]


def _base() -> fd.DriveParameters:
    # the force offset starts nonzero: the fit works in factors on the start
    return fd.preset("linear-motor-example").replace_path("disturbances.load_force", 5.0)


@pytest.mark.parametrize("mass, fc, fv, offset", [(26.0, 18.0, 80.0, 12.0),
                                                   (15.0, 11.0, 45.0, -6.0)])
def test_emps_layout_record_recovers_mass_friction_and_offset(tmp_path, mass: float, fc: float,
                                                              fv: float, offset: float) -> None:
    """Mass, Coulomb and viscous friction and the force offset, fitted from the position
    reference (input), the measured position and the motor force (fitted): each generating
    value inside its 95 % interval, determined, the model not called inadequate."""
    truth = (_base().replace_path("table.mass", mass)
             .replace_path("friction.guide.positive.coulomb_force", fc)
             .replace_path("friction.guide.positive.viscous_coefficient", fv)
             .replace_path("disturbances.load_force", offset))
    emps_layout(tmp_path / "estimation.mat", truth, drive=DRIVE)
    rec = read_rig_record(tmp_path / "estimation.mat", parse_map(MAP), _base(), drive=DRIVE)
    assert set(rec.experiment.signals) == {"table_position", "motor_current"}
    assert any("force vir compared as the motor_current" in n for n in rec.notes)
    base = _base()
    if offset < 0:
        base = base.replace_path("disturbances.load_force", -5.0)
    result = fit_drive(base, [rec.experiment], FREE, drive=DRIVE, profile=False)
    assert result.inadequate is None
    for e, true_value in zip(result.estimates, (mass, fc, fv, offset), strict=True):
        assert e.low <= true_value <= e.high, (e.path, e.value, e.low, e.high)
        assert e.determined, e.issue


def test_nan_runs_duplicates_and_irregular_steps_are_handled_and_stated(tmp_path) -> None:
    truth = _base()
    emps_layout(tmp_path / "r.mat", truth, drive=DRIVE, duration=0.6)
    d = sio.loadmat(tmp_path / "r.mat")
    t, qm = d["t"].ravel(), d["qm"].ravel()
    qm[100:104] = np.nan  # a sensor drop-out of 4 samples …
    qm[300] = np.nan  # … and one of 1
    t[200] = t[199]  # a duplicated time stamp
    t[400:] += 0.0004  # a shifted clock: irregular steps
    sio.savemat(tmp_path / "r.mat", {**{k: d[k] for k in ("qg", "vir")}, "t": t[:, None],
                                     "qm": qm[:, None]})
    rec = read_rig_record(tmp_path / "r.mat", parse_map(MAP), truth, drive=DRIVE)
    notes = " | ".join(rec.notes)
    assert "2 run(s) of NaN or infinite samples (5 samples) dropped" in notes
    assert "1 duplicated time stamp(s)" in notes
    assert "irregular sample steps" in notes
    assert rec.experiment.time.size == t.size - 5 - 1
    assert np.all(np.diff(rec.experiment.time) > 0)
    assert all("\n" not in n for n in rec.notes)


def _v73(path, **arrays: np.ndarray) -> None:
    """A MATLAB v7.3 file: HDF5 behind a 512-byte user block whose 128-byte header carries
    version 0x0200 (the layout scipy.io detects and does not read)."""
    import h5py

    with h5py.File(path, "w", userblock_size=512) as f:
        for k, v in arrays.items():
            f.create_dataset(k, data=np.asarray(v)[None, :])  # MATLAB stores columns transposed
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: test HDF5 schema 1.00 ."
    with open(path, "r+b") as f:
        f.write(header.ljust(116, b" ") + b"\0" * 8 + b"\x00\x02" + b"IM")


def test_v73_read_through_h5py_or_refused_in_one_line(tmp_path, monkeypatch) -> None:
    truth = _base()
    emps_layout(tmp_path / "r.mat", truth, drive=DRIVE, duration=0.4)
    d = sio.loadmat(tmp_path / "r.mat")
    _v73(tmp_path / "v73.mat", **{k: d[k].ravel() for k in ("t", "qg", "qm", "vir")})
    rec = read_rig_record(tmp_path / "v73.mat", parse_map(MAP), truth, drive=DRIVE)
    old = read_rig_record(tmp_path / "r.mat", parse_map(MAP), truth, drive=DRIVE)
    np.testing.assert_array_equal(rec.experiment.time, old.experiment.time)
    np.testing.assert_array_equal(rec.experiment.signals["table_position"],
                                  old.experiment.signals["table_position"])
    monkeypatch.setattr(rr.importlib.util, "find_spec",
                        lambda name, *a: None if name == "h5py" else object())
    with pytest.raises(FitError, match="v7.3") as err:
        read_rig_record(tmp_path / "v73.mat", parse_map(MAP), truth, drive=DRIVE)
    assert "\n" not in str(err.value) and "h5py" in str(err.value)


@pytest.mark.parametrize("items, words", [
    (["time=t position=qm reference=qg force=vire"], "no variable 'vire'"),
    (["time=t position=qm reference=qm"], "given two roles"),
    (["time=t position=qm voltage=vir reference=qg"], "unknown role 'voltage'"),
    # a torque is a role since the open-loop replay, and only as its input
    (["time=t position=qm torque=vir reference=qg"], "replayed only with --input torque"),
    (["time=t position=qm"], "exactly one of reference"),
    (["time=t position=qm reference=qg", "speed_reference=vir"], "exactly one of reference"),
    (["time=t reference=qg"], "no measured signal"),
    (["time=t position=qm reference=qg position=vir"], "given twice"),
])
def test_bad_map_refused_in_one_line_before_any_simulation(tmp_path, monkeypatch, items,
                                                           words: str) -> None:
    emps_layout(tmp_path / "r.mat", _base(), drive=DRIVE, duration=0.3)
    import feeddrive.engine.simulate as sim

    def refuse(*a: object, **k: object) -> None:
        raise AssertionError("a simulation ran")

    monkeypatch.setattr(sim, "simulate", refuse)
    with pytest.raises(FitError, match=words) as err:
        read_rig_record(tmp_path / "r.mat", parse_map(items), _base(), drive=DRIVE)
    assert "\n" not in str(err.value)


def test_force_on_a_drive_with_two_motors_is_refused(tmp_path) -> None:
    emps_layout(tmp_path / "r.mat", _base(), drive=DRIVE, duration=0.3)
    with pytest.raises(FitError, match="DDFS drives its table with 2 motors"):
        read_rig_record(tmp_path / "r.mat", parse_map(MAP), fd.preset("wang2021"),
                        drive="ddfs")
