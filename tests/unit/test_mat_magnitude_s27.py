"""`fit --map` / `validate --map` hold a .mat record's values to what a feed drive can show.

A .mat carries no units: a variable without a bracketed unit is read in its role's SI unit.
Before, the only check was a time whose steps are exactly 1 (ms read as s), so a record in mm,
in ms at any other rate, or a current in mA was read 1000× off and fitted as such; and no
value was held to the bound a CSV column is held to (io.measured.LARGEST_MAGNITUDE).  Now
each is refused in one line naming ``--map ROLE=VARIABLE``, what was seen, the unit assumed
and the unit it is likelier in.

Also two misreadings of MATLAB v7.3 (HDF5) files, written here with h5py in MATLAB's layout:
an empty array, which MATLAB stores as its dimensions with a ``MATLAB_empty`` attribute, was
read as the two samples [0, 0] ("the mapped variables differ in length"), and text
(``MATLAB_class`` char, uint16 character codes) passed as numbers.
"""

from __future__ import annotations

import re
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io as sio
from test_mat_struct_map_s27 import _v73
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis.fit import FitError
from feeddrive.analysis.rig_record import parse_map, read_rig_record
from feeddrive.cli import app
from feeddrive.io.measured import LARGEST_MAGNITUDE
from feeddrive.parameters import ParameterError

N = 1001  # samples: 1 kHz, 1 s


def _record() -> dict[str, np.ndarray]:
    """A 1-s record in SI: time [s], a minimum-jerk move of 0.2 m from 0.01 m as the position
    reference and (1 µm behind, in 1-µm counts) the measured position [m], its speed [m/s],
    a current of 0.5 A with noise [A]."""
    rng = np.random.default_rng(3)
    t = np.arange(N) * 1e-3
    tau = np.clip((t - 0.05) / 0.9, 0.0, 1.0)
    qg = 0.01 + 0.2 * (10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5)
    qm = np.round((qg - 1e-6) / 1e-6) * 1e-6
    v = 0.2 / 0.9 * 30 * tau ** 2 * (1 - tau) ** 2
    cur = 0.5 + 0.01 * rng.standard_normal(N)
    return {"t": t, "qg": qg, "qm": qm, "v": v, "cur": cur}


def _mat(path: Path, **scaled: float) -> Path:
    """The record as MATLAB N×1 columns, each variable times ``scaled[name]`` (1e3: in mm,
    ms, mm/s or mA)."""
    sio.savemat(path, {k: (v * scaled.get(k, 1.0))[:, None] for k, v in _record().items()})
    return path


SI_MAP = "time=t reference=qg position=qm current=cur"
CDFS = "wang2021"  # cdfs, screw.length = 0.8 m (Wang2021 Table 2), no current limit
LIMITED = "wang2021-drive"  # the same with controller.current_limit 17 A, 300 V


def _refusal(path: Path, items: str, preset: str = CDFS, drive: str = "cdfs") -> str:
    with pytest.raises((ParameterError, FitError)) as err:
        read_rig_record(path, parse_map([items]), fd.preset(preset), drive=drive)
    message = str(err.value)
    assert "\n" not in message
    return message


def test_a_plausible_si_record_is_read_unchanged(tmp_path: Path) -> None:
    """The checks refuse nothing a drive shows: the SI record reads as it is."""
    rec = read_rig_record(_mat(tmp_path / "si.mat"), parse_map([SI_MAP]), fd.preset(LIMITED))
    s = _record()
    np.testing.assert_array_equal(rec.experiment.signals["table_position"], s["qm"] - s["qm"][0])
    np.testing.assert_array_equal(rec.experiment.signals["screw_current"], s["cur"])


# ------------------------------------------------------------------ read 1000× off

def test_a_position_in_mm_longer_than_the_screw_is_refused(tmp_path: Path) -> None:
    """A 0.2-m move in mm read in m is a 200-m stroke: longer than the wang2021 screw (0.8 m,
    Wang2021 Table 2), refused suggesting mm; before, fitted as a 200-m move."""
    path = _mat(tmp_path / "mm.mat", qg=1e3, qm=1e3)
    message = _refusal(path, "time=t reference=qg[mm] position=qm current=cur")
    assert message == (f"{path}: --map position=qm: a stroke of 200 m read in m (no unit "
                       "given), longer than the table's travel (screw.length = 0.8 m); if it "
                       "is in mm write position=qm[mm] (position=qm[m] if it is in m)")
    # the reference too, and the suggested map reads the record
    assert _refusal(path, "time=t reference=qg position=qm[mm] current=cur").startswith(
        f"{path}: --map reference=qg: a stroke of 200 m read in m (no unit given)")
    rec = read_rig_record(path, parse_map(["time=t reference=qg[mm] position=qm[mm] "
                                           "current=cur"]), fd.preset(CDFS))
    np.testing.assert_allclose(np.ptp(rec.experiment.signals["table_position"]), 0.2,
                               rtol=1e-5)


def test_a_position_in_mm_of_a_linear_motor_is_refused_by_its_mean_speed(
        tmp_path: Path) -> None:
    """A linear motor has no screw to bound its travel: the 200-m stroke in 1 s asks a mean
    speed of 200 m/s, beyond any feed drive (units.LARGEST_SPEED, 100 m/s)."""
    path = _mat(tmp_path / "mm.mat", qg=1e3, qm=1e3)
    message = _refusal(path, "time=t reference=qg[mm] position=qm current=cur",
                       "linear-motor-example", "linear-motor")
    assert message == (f"{path}: --map position=qm: a stroke of 200 m in 1 s read in m (no "
                       "unit given): a mean speed of 200 m/s, beyond the axis's 100 m/s (no "
                       "feed drive is faster); if it is in mm write position=qm[mm] "
                       "(position=qm[m] if it is in m)")


@pytest.mark.parametrize("rate_hz, jitter", [(2000.0, 0.0), (8000.0, 0.0), (1000.0, 1e-3)])
def test_a_time_in_ms_with_steps_other_than_1_is_refused(tmp_path: Path, rate_hz: float,
                                                         jitter: float) -> None:
    """A time in ms read in s at 2 kHz (steps 0.5), 8 kHz (0.125) or 1 kHz with a jittered
    clock (steps about 1, not exactly: the old check's only case missed): steps of 0.1 s
    or more (LARGEST_UNITLESS_STEP), refused suggesting ms; before, read as a 1000× longer
    record."""
    rng = np.random.default_rng(1)
    step_ms = 1e3 / rate_hz
    t_ms = np.arange(N) * step_ms + jitter * rng.uniform(-1.0, 1.0, N)
    s = _record()
    path = tmp_path / "ms.mat"
    sio.savemat(path, {"t": t_ms[:, None], "qg": s["qg"][:, None], "qm": s["qm"][:, None],
                       "cur": s["cur"][:, None]})
    message = _refusal(path, SI_MAP)
    step = float(np.median(np.diff(t_ms)))
    assert message == (f"{path}: --map time=t: a median sample step of {step:.4g} s read in s "
                       f"(no unit given): a record at {1 / step:.3g} Hz, slower than a drive's "
                       "records are taken (steps < 0.1 s); if it is in ms write time=t[ms] "
                       "(time=t[s] if it is in s)")
    rec = read_rig_record(path, parse_map(["time=t[ms] reference=qg position=qm current=cur"]),
                          fd.preset(CDFS))
    assert rec.experiment.time[-1] == pytest.approx((N - 1) * step_ms * 1e-3, rel=1e-5)


def test_a_time_given_in_s_is_taken_as_given(tmp_path: Path) -> None:
    """A unit in the map is the user's word: a 0.5-s step written time=t[s] is read."""
    s = _record()
    path = tmp_path / "slow.mat"
    sio.savemat(path, {"t": (s["t"] * 500.0)[:, None], "qg": s["qg"][:, None],
                       "qm": s["qm"][:, None], "cur": s["cur"][:, None]})
    rec = read_rig_record(path, parse_map(["time=t[s] reference=qg position=qm current=cur"]),
                          fd.preset(CDFS))
    assert float(np.median(np.diff(rec.experiment.time))) == pytest.approx(0.5)


def test_a_current_in_ma_is_refused_against_the_controllers_limit(tmp_path: Path) -> None:
    """0.5 A in mA read in A is 500 A: beyond twice wang2021-drive's 17-A current limit
    (CURRENT_LIMIT_MARGIN), refused suggesting mA; before, fitted as 500 A."""
    path = _mat(tmp_path / "ma.mat", cur=1e3)
    message = _refusal(path, SI_MAP, LIMITED)
    top = float(np.max(np.abs(_record()["cur"] * 1e3)))
    assert message == (f"{path}: --map current=cur: a current of {top:.4g} A read in A (no "
                       "unit given), beyond 34 A (2 × the controller's limit, "
                       "controller.current_limit = 17 A); if it is in mA write "
                       "current=cur[mA] (current=cur[A] if it is in A)")
    rec = read_rig_record(path, parse_map(["time=t reference=qg position=qm current=cur[mA]"]),
                          fd.preset(LIMITED))
    np.testing.assert_allclose(rec.experiment.signals["screw_current"], _record()["cur"],
                               rtol=1e-12)


def test_a_current_in_ma_without_a_current_limit(tmp_path: Path) -> None:
    """wang2021 sets no current limit: a current above 2 × 1000 A (engine.options.
    NO_CURRENT_LIMIT, what feeddrive takes as none) is refused; 5 A in mA is 5000 A."""
    path = _mat(tmp_path / "ma.mat", cur=1e4)
    message = _refusal(path, SI_MAP, CDFS)
    assert re.fullmatch(rf"{re.escape(str(path))}: --map current=cur: a current of 5\d\d\d A "
                        r"read in A \(no unit given\), beyond 2000 A \(2 × 1000 A, the current "
                        r"feeddrive takes as no limit: the set gives none\); if it is in mA "
                        r"write current=cur\[mA\] \(current=cur\[A\] if it is in A\)", message)


def test_a_speed_in_mm_s_is_refused_against_the_axis_speed(tmp_path: Path) -> None:
    """A speed reference of at most 0.042 m/s in mm/s read in m/s is 42 m/s: beyond
    wang2021-drive's axis (its screw motor's no-load speed at 300 V, 1.59 m/s), though not
    beyond any feed drive (100 m/s); refused suggesting mm/s."""
    path = _mat(tmp_path / "v.mat", v=1e2)
    message = _refusal(path, "time=t speed_reference=v position=qm current=cur", LIMITED)
    top = float(np.max(_record()["v"] * 1e2))
    assert message.startswith(f"{path}: --map speed_reference=v: a speed of {top:.4g} m/s read "
                              "in m/s (no unit given), beyond the axis's 1.592 m/s (the screw "
                              "motor's no-load speed at the voltage limit: ")
    assert message.endswith("; if it is in mm/s write speed_reference=v[mm/s] "
                            "(speed_reference=v[m/s] if it is in m/s)")


# ------------------------------------------------------------------ the CSV bound

def test_a_value_beyond_any_feed_drive_is_refused_as_a_csv_column_is(tmp_path: Path) -> None:
    """The bound a CSV column is held to (LARGEST_MAGNITUDE: 1 km, 1e7 N), whatever the unit:
    a machine coordinate of 2 m in mm read in m (a small stroke, within the screw) names mm;
    a force of 2e7 N (a force has no smaller unit) and 2 km given in mm ask to check the
    unit.  Before, each was read."""
    s = _record()
    path = tmp_path / "big.mat"
    vir = 1e3 + 1e2 * np.sin(s["t"])
    vir[500] = 2e7
    sio.savemat(path, {"t": s["t"][:, None], "qg": (s["qg"] * 1e-2)[:, None],
                       "qm_mm": (2000.0 + s["qm"] * 1e-2 * 1e3)[:, None],
                       "far_mm": (2e6 + s["qm"] * 1e3)[:, None], "vir": vir[:, None]})
    assert LARGEST_MAGNITUDE["length"] == 1e3 and LARGEST_MAGNITUDE["force"] == 1e7
    message = _refusal(path, "time=t reference=qg position=qm_mm force=vir",
                       "linear-motor-example", "linear-motor")
    assert message == (f"{path}: --map position=qm_mm: a value of 2000.1 m is beyond any feed "
                       "drive (|length| ≤ 1000 m); if it is in mm write position=qm_mm[mm]")
    message = _refusal(path, "time=t reference=qg position=far_mm[mm] force=vir",
                       "linear-motor-example", "linear-motor")
    assert message == (f"{path}: --map position=far_mm[mm]: a value of 2.00001e+06 mm is beyond "
                       "any feed drive (|length| ≤ 1e+06 mm); check the variable's unit")
    message = _refusal(path, "time=t reference=qg force=vir", "linear-motor-example",
                       "linear-motor")
    assert message == (f"{path}: --map force=vir: a value of 2e+07 N is beyond any feed drive "
                       "(|force| ≤ 1e+07 N); check the variable's unit")


def test_the_cli_refuses_in_one_line(tmp_path: Path) -> None:
    """`feeddrive fit --map` prints the refusal in one line and exits 2, before any
    simulation."""
    path = _mat(tmp_path / "mm.mat", qg=1e3, qm=1e3)
    res = CliRunner().invoke(app, ["fit", str(path), "--free", "table.mass", "--map",
                                   "time=t reference=qg[mm] position=qm current=cur"])
    assert res.exit_code == 2, res.output
    assert "--map position=qm: a stroke of 200 m read in m (no unit given)" in res.output
    assert "write position=qm[mm]" in res.output


# ------------------------------------------------------------------ v7.3 misreadings

def _v73_record(path: Path) -> Path:
    """The SI record as a v7.3 file (test_mat_struct_map_s27's writer, MATLAB's layout), with
    what MATLAB writes for an empty array — its dimensions, uint64, ``MATLAB_empty`` = 1 — and
    for text — uint16 character codes, ``MATLAB_class`` char — as variables and as fields of
    the 1×1 struct ``rec``."""
    s = _record()
    _v73(path, {"t": s["t"], "qg": s["qg"], "qm": s["qm"], "cur": s["cur"],
                "rec": {"t": s["t"]}})
    with h5py.File(path, "a") as f:
        for where, shape in (("empty", (0, 1)), ("rec/cur", (0, 0))):
            ds = f.create_dataset(where, data=np.array(shape, np.uint64))
            ds.attrs["MATLAB_class"] = np.bytes_("double")
            ds.attrs["MATLAB_empty"] = np.uint8(1)
        for where, text in (("label", ("axis x, run 3; " * N)[:N]), ("rec/name", "axis x")):
            ds = f.create_dataset(where, data=np.array([[ord(c) for c in text]], np.uint16).T)
            ds.attrs["MATLAB_class"] = np.bytes_("char")
            ds.attrs["MATLAB_int_decode"] = np.int32(2)
    return path


@pytest.mark.parametrize("spec, what", [
    ("empty", "'empty' in {src} is empty ([] in MATLAB): no samples to read"),
    ("rec.cur", "'rec.cur' in {src} is empty ([] in MATLAB): no samples to read"),
    ("label", "'label' in {src} is text (a MATLAB char array), not a numeric vector"),
    ("rec.name", "'rec.name' in {src} is text (a MATLAB char array), not a numeric vector"),
])
def test_v73_empty_and_text_are_refused_as_what_they_are(tmp_path: Path, spec: str,
                                                         what: str) -> None:
    """Before, an empty read as [0, 0] ("the mapped variables differ in length"), and a
    text of N characters as a current of N character codes (32 … 120 A), fitted."""
    path = _v73_record(tmp_path / "v73.mat")
    with pytest.raises(NotImplementedError):  # scipy.io does not read it: h5py does
        sio.loadmat(path)
    with pytest.raises(FitError) as err:
        read_rig_record(path, parse_map([f"time=t reference=qg position=qm current={spec}"]),
                        fd.preset(CDFS))
    assert str(err.value) == f"--map current={spec}: {what.format(src=path)}"
    # the record's numbers read as they are
    rec = read_rig_record(path, parse_map([SI_MAP]), fd.preset(CDFS))
    np.testing.assert_array_equal(rec.experiment.signals["screw_current"], _record()["cur"])


def test_v5_empty_column_is_refused_as_empty(tmp_path: Path) -> None:
    """A 0×1 variable of a v5 file (scipy.io) read as a vector of no samples: before,
    "the mapped variables differ in length"."""
    s = _record()
    path = tmp_path / "v5.mat"
    sio.savemat(path, {"t": s["t"][:, None], "qg": s["qg"][:, None], "qm": s["qm"][:, None],
                       "cur": np.zeros((0, 1))})
    with pytest.raises(FitError) as err:
        read_rig_record(path, parse_map([SI_MAP]), fd.preset(CDFS))
    assert str(err.value) == (f"--map current=cur: 'cur' in {path} is empty ([] in MATLAB): no "
                              "samples to read")
