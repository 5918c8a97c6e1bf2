"""`fit --map` and `validate --map` read a MATLAB struct's fields by their dotted path
(`time=rec.t`, `position=feeddrive.table_position`, `feeddrive.x.table_position`): before, only
top-level variables were read, so neither feeddrive's own `.mat` export (one struct
`feeddrive`, feeddrive.io.results) nor a record that keeps its signals in a struct could be
fitted or validated ("no variable 'feeddrive.time'").  v5 files through scipy.io, v7.3 (HDF5,
MATLAB's layout: a 1×1 struct a group, a struct array's fields arrays of object references)
through h5py; each refusal in one line."""

from __future__ import annotations

import json
import re
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io as sio
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis.fit import FitError
from feeddrive.analysis.rig_record import parse_map, read_rig_record
from feeddrive.cli import app
from feeddrive.parameters import ParameterError

N = 201  # samples of the records below: 1 kHz, 0.2 s


def _signals() -> dict[str, np.ndarray]:
    """A 0.2-s record in SI: time [s], position reference and measured position [m] (offset
    and 1-µm counts), current [A]."""
    rng = np.random.default_rng(7)
    t = np.arange(N) * 1e-3
    qg = 0.01 + np.cumsum(np.clip(t / 0.05, 0.0, 1.0)) * 1e-6  # 1 mm/s after a 50-ms ramp
    qm = np.round((qg - 2e-6) / 1e-6) * 1e-6
    cur = 0.1 + 1e-3 * rng.standard_normal(N)
    return {"t": t, "qg": qg, "qm": qm, "cur": cur}


def _col(v: np.ndarray) -> np.ndarray:
    return np.asarray(v, dtype=float)[:, None]  # an N×1 column, as MATLAB keeps signals


def _struct_mat(path: Path) -> Path:
    """A v5 file holding the record twice, as structs (a dict of dicts in scipy.io.savemat):
    ``rec`` with time in ms and positions in mm, and ``rig.x`` (nested) in SI."""
    s = _signals()
    rec = {"t": _col(s["t"] * 1e3), "ref": _col(s["qg"] * 1e3), "pos": _col(s["qm"] * 1e3),
           "cur": _col(s["cur"]), "info": {"operator": "test"}}
    rig = {"x": {"t": _col(s["t"]), "qg": _col(s["qg"]), "qm": _col(s["qm"]),
                 "cur": _col(s["cur"])}}
    sio.savemat(path, {"rec": rec, "rig": rig, "note": "struct record"})
    return path


def _top_mat(path: Path) -> Path:
    """The same record as top-level variables in SI (the layout --map read before)."""
    sio.savemat(path, {k: _col(v) for k, v in _signals().items()})
    return path


STRUCT_MAP = "time=rec.t[ms] reference=rec.ref[mm] position=rec.pos[mm] current=rec.cur"
NESTED_MAP = "time=rig.x.t reference=rig.x.qg position=rig.x.qm current=rig.x.cur"
TOP_MAP = "time=t reference=qg position=qm current=cur"


@pytest.mark.parametrize("items", [STRUCT_MAP, NESTED_MAP])
def test_struct_fields_are_read_by_dotted_path_in_si(tmp_path: Path, items: str) -> None:
    """A struct's fields (units in brackets after the path) read as the same record in SI as
    top-level variables; before, 'no variable 'rec.t''."""
    params = fd.preset("wang2021")
    rec = read_rig_record(_struct_mat(tmp_path / "s.mat"), parse_map([items]), params)
    top = read_rig_record(_top_mat(tmp_path / "top.mat"), parse_map([TOP_MAP]), params)
    s = _signals()
    # the [mm] field in metres, relative to its first sample (read_rig_record's rule)
    np.testing.assert_allclose(rec.experiment.signals["table_position"], s["qm"] - s["qm"][0],
                               rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(rec.experiment.time, s["t"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(rec.experiment.table_speed, top.experiment.table_speed,
                               rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(rec.experiment.signals["screw_current"], s["cur"])
    assert rec.mapping == parse_map([items])


def _v73(path: Path, variables: dict[str, object]) -> Path:
    """A MATLAB v7.3 file in MATLAB's layout: HDF5 behind a 512-byte user block whose header
    carries version 0x0200; a 1×1 struct a group (``MATLAB_class`` struct) of its fields, a
    numeric array stored transposed, a struct array (a list of dicts) a group whose fields are
    arrays of object references into ``#refs#`` with no ``MATLAB_class``."""
    with h5py.File(path, "w", userblock_size=512) as f:
        refs = f.create_group("#refs#")

        def put(group: h5py.Group, name: str, value: object) -> None:
            if isinstance(value, dict):
                sub = group.create_group(name)
                sub.attrs["MATLAB_class"] = np.bytes_("struct")
                for k, v in value.items():
                    put(sub, k, v)
            elif isinstance(value, list):
                sub = group.create_group(name)
                sub.attrs["MATLAB_class"] = np.bytes_("struct")
                for k in value[0]:
                    targets = []
                    for i, element in enumerate(value):
                        ds = refs.create_dataset(f"{name}_{k}_{i}",
                                                 data=np.asarray(element[k], float)[None, :])
                        ds.attrs["MATLAB_class"] = np.bytes_("double")
                        targets.append(ds.ref)
                    sub.create_dataset(k, data=np.array(targets, dtype=h5py.ref_dtype)[:, None])
            else:
                ds = group.create_dataset(name, data=np.asarray(value, float)[None, :])
                ds.attrs["MATLAB_class"] = np.bytes_("double")

        for k, v in variables.items():
            put(f, k, v)
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: test HDF5 schema 1.00 ."
    with open(path, "r+b") as fh:
        fh.write(header.ljust(116, b" ") + b"\0" * 8 + b"\x00\x02" + b"IM")
    return path


def _v73_record(path: Path) -> Path:
    s = _signals()
    return _v73(path, {"rig": {"x": {"t": s["t"], "qg": s["qg"] * 1e3, "qm": s["qm"],
                                     "cur": s["cur"]}},
                       "runs": [{"t": s["t"]}, {"t": s["t"]}, {"t": s["t"]}],
                       "t0": s["t"]})


def test_v73_struct_fields_are_read_by_dotted_path(tmp_path: Path) -> None:
    params = fd.preset("wang2021")
    path = _v73_record(tmp_path / "v73.mat")
    with pytest.raises(NotImplementedError):  # scipy.io does not read it: h5py does
        sio.loadmat(path)
    rec = read_rig_record(path, parse_map(["time=rig.x.t reference=rig.x.qg[mm] "
                                           "position=rig.x.qm current=rig.x.cur"]), params)
    top = read_rig_record(_top_mat(tmp_path / "top.mat"), parse_map([TOP_MAP]), params)
    np.testing.assert_array_equal(rec.experiment.time, top.experiment.time)
    np.testing.assert_array_equal(rec.experiment.signals["table_position"],
                                  top.experiment.signals["table_position"])
    np.testing.assert_allclose(rec.experiment.table_speed, top.experiment.table_speed,
                               rtol=1e-9, atol=1e-12)


# ------------------------------------------------------------------ the refusals

ROLES = {"time": "rec.t[ms]", "reference": "rec.ref[mm]", "position": "rec.pos[mm]",
         "current": "rec.cur"}


def _struct_array(path: Path) -> Path:
    """A v5 file with ``runs``, a 1×3 struct array (a record array in scipy.io.savemat)."""
    t = _col(np.arange(N) * 1e-3)
    runs = np.zeros((1, 3), dtype=[("t", object), ("pos", object)])
    for k in range(3):
        runs[0, k] = (t, t)
    sio.savemat(path, {"runs": runs})
    return path


@pytest.mark.parametrize("role, spec, message", [
    ("position", "rc.pos[mm]", "--map position=rc.pos[mm]: no variable 'rc' in {src} (it "
     "holds: note, rec, rig)"),
    ("position", "rec.ps[mm]", "--map position=rec.ps[mm]: no field 'ps' in struct 'rec' of "
     "{src} (its fields: t, ref, pos, cur, info)"),
    ("position", "rig.x.q[mm]", "--map position=rig.x.q[mm]: no field 'q' in struct 'rig.x' "
     "of {src} (its fields: t, qg, qm, cur)"),
    ("current", "rig.x", "--map current=rig.x: 'rig.x' in {src} is a struct, not a numeric "
     "vector; name one of its fields, rig.x.FIELD (its fields: t, qg, qm, cur)"),
    ("current", "rec.info", "--map current=rec.info: 'rec.info' in {src} is a struct, not a "
     "numeric vector; name one of its fields, rec.info.FIELD (its fields: operator)"),
    ("current", "rec.cur.x", "--map current=rec.cur.x: 'rec.cur' in {src} is not a struct "
     "(shape (201, 1)): it has no field 'x'"),
    ("current", "note", "--map current=note: 'note' in {src} is not a numeric vector (shape "
     "(1,))"),
])
def test_a_bad_struct_path_is_refused_in_one_line(tmp_path: Path, role: str, spec: str,
                                                  message: str) -> None:
    path = _struct_mat(tmp_path / "s.mat")
    with pytest.raises(FitError) as err:
        read_rig_record(path, {**ROLES, role: spec}, fd.preset("wang2021"))
    assert str(err.value) == message.format(src=path)


def test_a_struct_array_is_refused_saying_its_size(tmp_path: Path) -> None:
    path = _struct_array(tmp_path / "a.mat")
    for spec in ("runs.t", "runs"):
        with pytest.raises(FitError) as err:
            read_rig_record(path, {"time": spec, "speed_reference": "runs.pos",
                                   "position": "runs.pos"}, fd.preset("wang2021"))
        assert str(err.value) == (
            f"--map time={spec}: 'runs' in {path} is a struct array of 3 elements; the map "
            "reads a variable or a field of a 1×1 struct (no indexing): save the element "
            "wanted as its own variable")


@pytest.mark.parametrize("spec, message", [
    ("rig.x.q", "no field 'q' in struct 'rig.x' of {src} (its fields: cur, qg, qm, t)"),
    ("rig.x", "'rig.x' in {src} is a struct, not a numeric vector; name one of its fields, "
     "rig.x.FIELD (its fields: cur, qg, qm, t)"),
    ("runs.t", "'runs' in {src} is a struct array of 3 elements; the map reads a variable or "
     "a field of a 1×1 struct (no indexing): save the element wanted as its own variable"),
    ("rg.x.qm", "no variable 'rg' in {src} (it holds: rig, runs, t0)"),
])
def test_v73_bad_struct_paths_are_refused_in_one_line(tmp_path: Path, spec: str,
                                                      message: str) -> None:
    path = _v73_record(tmp_path / "v73.mat")
    roles = {"time": "rig.x.t", "reference": "rig.x.qg[mm]", "position": spec,
             "current": "rig.x.cur"}
    with pytest.raises(FitError) as err:
        read_rig_record(path, roles, fd.preset("wang2021"))
    assert str(err.value) == f"--map position={spec}: " + message.format(src=path)


@pytest.mark.parametrize("item, message", [
    ("position=runs(2).pos", r"--map position = 'runs\(2\)\.pos': expected VARIABLE or a 1×1 "
     r"struct's field STRUCT\.FIELD, e\.g\. rec\.pos\[mm\]; an element of a struct array or "
     r"cell \(rec\(2\)\.pos, c\{1\}\) is not read: save it as its own variable"),
    ("position=rec..pos[mm]", r"--map position = 'rec\.\.pos\[mm\]': expected VARIABLE or a "
     r"struct's field STRUCT\.FIELD, e\.g\. rec\.pos\[mm\]: a name between dots is empty"),
    ("position=rec.[mm]", r"--map position = 'rec\.\[mm\]': expected VARIABLE or a struct's "
     r"field"),
])
def test_indexing_and_empty_names_in_a_path_are_refused_by_the_map(item: str,
                                                                   message: str) -> None:
    with pytest.raises(ParameterError) as err:
        parse_map([f"time=rec.t reference=rec.ref current=rec.cur {item}"])
    assert err.value.field == "--map position"
    assert "\n" not in str(err.value)
    assert re.match(message, str(err.value)), str(err.value)


def test_the_cli_refuses_a_missing_field_in_one_line(tmp_path: Path) -> None:
    _struct_mat(tmp_path / "s.mat")
    res = CliRunner().invoke(app, ["fit", str(tmp_path / "s.mat"), "--free",
                                   "friction.screw.positive.coulomb_force", "--map",
                                   STRUCT_MAP.replace("rec.cur", "rec.current")])
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "no field 'current' in struct 'rec'" in lines[0], res.output


# ------------------------------------------------------------------ the round trip


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two CDFS runs of wang2021 written by `feeddrive simulate --output run.mat` (1-ms
    samples, the default output interval): 4 mm/s to fit, 6 mm/s held out."""
    d = tmp_path_factory.mktemp("matrun")
    for name, speed in (("fit.mat", "4"), ("held.mat", "6")):
        res = CliRunner().invoke(app, ["simulate", "--drive", "cdfs", "--table-speed", speed,
                                       "--duration", "1.5", "--method", "dopri5",
                                       "--output", str(d / name)])
        assert res.exit_code == 0, res.output
    return d


#: the map of a feeddrive .mat run: its struct ``feeddrive`` (feeddrive.io.results), SI
RUN_MAP = ("time=feeddrive.time speed_reference=feeddrive.table_speed_reference "
           "position=feeddrive.table_position current=feeddrive.screw_current")


def test_feeddrives_own_mat_export_is_fitted_and_validated(simulated: Path) -> None:
    """The round trip a user makes: simulate to .mat, fit the screw's Coulomb force on it
    with --map through the struct's fields, validate the fit on a held-out .mat run."""
    held = sio.loadmat(simulated / "held.mat")["feeddrive"]
    assert held.shape == (1, 1) and "table_speed_reference" in held.dtype.names
    fitted = simulated / "fitted.toml"
    res = CliRunner().invoke(app, ["fit", str(simulated / "fit.mat"), "--drive", "cdfs",
                                   "--free", "friction.screw.positive.coulomb_force",
                                   "--no-profile", "--map", RUN_MAP, "--out", str(fitted),
                                   "--json"])
    assert res.exit_code == 0, res.output
    (estimate,) = json.loads(res.stdout)["estimates"]
    # the run's own value, wang2021 Table 1 F_c (screw, +)
    assert estimate["value"] == pytest.approx(73.4, rel=1e-6)
    res = CliRunner().invoke(app, ["validate", str(fitted), str(simulated / "held.mat"),
                                   "--map", RUN_MAP, "--json"])
    assert res.exit_code == 0, res.output
    scores = {s["signal"]: s for s in json.loads(res.stdout)["signals"]}
    assert set(scores) == {"table_position", "screw_current"}
    assert all(s["fit_percent"] > 99.0 for s in scores.values()), scores


def test_a_machine_runs_axis_struct_is_read_by_its_nested_path(tmp_path: Path) -> None:
    """A machine's .mat run keeps each axis in a struct (feeddrive.x.table_position): its
    fields read by the nested path are the file's own values; the axis itself is refused as
    a struct, naming its fields."""
    path = tmp_path / "machine.mat"
    res = CliRunner().invoke(app, ["simulate", "--machine", "xy-table", "--contour", "line",
                                   "--length", "2", "--feed", "120", "--output", str(path)])
    assert res.exit_code == 0, res.output
    x = sio.loadmat(path)["feeddrive"][0, 0]["x"][0, 0]
    roles = parse_map(["time=feeddrive.time speed_reference=feeddrive.x.table_speed_reference "
                       "position=feeddrive.x.table_position[m] current=feeddrive.x.screw_current"])
    rec = read_rig_record(path, roles, fd.preset("wang2021"))
    position = x["table_position"].ravel()
    np.testing.assert_array_equal(rec.experiment.signals["table_position"],
                                  position - position[0])
    np.testing.assert_array_equal(rec.experiment.signals["screw_current"],
                                  x["screw_current"].ravel())
    with pytest.raises(FitError, match=r"^--map position=feeddrive\.x: 'feeddrive\.x' in .* is "
                       r"a struct, not a numeric vector; name one of its fields, "
                       r"feeddrive\.x\.FIELD \(its fields: screw_angle, .*table_position"):
        read_rig_record(path, {**roles, "position": "feeddrive.x"}, fd.preset("wang2021"))
