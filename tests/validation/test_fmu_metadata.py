"""What an importer's dialog reads from the FMU (issue 38 item 2): display units as the CLI
speaks (mm, mm/s, µm, rpm, N/µm), min/max from the parameter ranges, nominal magnitudes of
the states, author, version, copyright, licence and generation time, and the licence files
of what the FMU carries."""

from __future__ import annotations

import ctypes
import datetime
import math
import zipfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from fmu_helpers import SharedExports, require_c_compiler

import feeddrive as fd
from feeddrive import __version__
from feeddrive.fmu import export_fmu, solver_starts
from feeddrive.fmu.description import state_nominals
from feeddrive.fmu.model import build
from feeddrive.parameters import preset
from feeddrive.units import ENGINEERING

fmpy = pytest.importorskip("fmpy")
require_c_compiler()

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def fmus(shared_fmus: SharedExports) -> dict[tuple[int, str], Path]:
    """The DDFS (wang2021) in each FMI version and kind, exported once in the session
    (``shared_fmus``: test_fmu.py and test_fmu_directional.py read the same)."""
    return {(fmi, kind): Path(shared_fmus.drive(preset("wang2021"), "ddfs", fmi=fmi,
                                                kind=kind).path)
            for fmi in (2, 3) for kind in ("cs", "me")}


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("kind", ["cs", "me"])
def test_valid_with_display_units_as_the_cli_speaks(fmus: dict, shared_fmus: SharedExports,
                                                    fmi: int, kind: str) -> None:
    from fmpy import read_model_description

    path = fmus[(fmi, kind)]
    # fmpy.validation.validate_fmu, run once for this file (test_fmu.py asks too)
    assert shared_fmus.problems(path) == []
    md = read_model_description(str(path))
    v = {x.name: x for x in md.modelVariables}
    factors = {(u.name, d.name): (d.factor, d.offset) for u in md.unitDefinitions
               for d in u.displayUnits}
    # display value = factor × SI value (FMI 2.0.4 Sect. 2.2.2); feeddrive.units.ENGINEERING
    # is the CLI's table: mm = 1e3 m, mm/s = 1e3 m/s, N/µm = 1e-6 N/m; 1 rpm = 2π/60 rad/s
    shown = {"table_position": ("m", "mm"), "table_speed": ("m/s", "mm/s"),
             "following_error": ("m", "µm"), "screw_speed": ("rad/s", "rpm"),
             "friction.guide.bristle_stiffness": ("N/m", "N/µm"),
             "controller.screw.grat_q": ("m", "µm"), "table.mass": ("kg", None)}
    for name, (unit, display) in shown.items():
        assert (v[name].unit, v[name].displayUnit) == (unit, display), name
    assert float(factors[("m", "mm")][0]) == ENGINEERING["m"][1] == 1e3
    assert float(factors[("m/s", "mm/s")][0]) == ENGINEERING["m/s"][1]
    assert float(factors[("N/m", "N/µm")][0]) == ENGINEERING["N/m"][1] == 1e-6
    assert float(factors[("m", "µm")][0]) == 1e6
    assert float(factors[("rad/s", "rpm")][0]) == pytest.approx(60.0 / (2.0 * math.pi),
                                                                 rel=1e-15)
    # a position of 0.4 mm shows as 0.4 mm in the dialog, not 0.0004 m
    assert 0.0004 * float(factors[("m", "mm")][0]) == pytest.approx(0.4)


@pytest.mark.parametrize("fmi", [2, 3])
def test_states_declare_the_nominals_the_binary_reports(fmus: dict, fmi: int,
                                                        tmp_path: Path) -> None:
    """nominal on every continuous state in the XML = what
    fmiGetNominalsOfContinuousStates returns (model exchange) = the fixed magnitudes 1e-10 m,
    1e-8 m/s, 1e-6 A over 1e-6 (a position: 1e-4 m), whatever the export's tolerances."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model
    from fmpy.fmi3 import FMU3Model

    path = fmus[(fmi, "me")]
    md = read_model_description(str(path))
    states = [x for x in md.modelVariables if x.derivative is not None]
    xml = np.array([float(x.derivative.nominal) for x in states])
    fm = replace(build(preset("wang2021"), "ddfs", 0.4),
                 solver_starts=solver_starts(preset("wang2021"), 0.0, 0.0))
    assert np.array_equal(xml, state_nominals(fm))
    position = [x.derivative.name for x in states].index("table_position")
    assert xml[position] == 1e-10 / 1e-6  # a magnitude, not the export's tolerance
    cls = FMU2Model if fmi == 2 else FMU3Model
    fmu = cls(guid=md.guid, unzipDirectory=extract(str(path), unzipdir=str(tmp_path / "u")),
              modelIdentifier=md.modelExchange.modelIdentifier, instanceName="n")
    fmu.instantiate()
    nominals = np.zeros(len(states))
    fmu.getNominalsOfContinuousStates(
        nominals.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(states))
    assert np.array_equal(nominals, xml)
    fmu.freeInstance()


@pytest.mark.parametrize("fmi", [2, 3])
def test_provenance_and_licence_files(fmus: dict, fmi: int) -> None:
    from fmpy import read_model_description

    path = fmus[(fmi, "cs")]
    md = read_model_description(str(path))
    assert md.author == "the feeddrive maintainers"  # pyproject.toml authors
    assert md.version == __version__
    assert md.generationTool == f"feeddrive {__version__}"
    made = datetime.datetime.strptime(md.generationDateAndTime, "%Y-%m-%dT%H:%M:%SZ")
    age = datetime.datetime.now(datetime.UTC).replace(tzinfo=None) - made
    assert datetime.timedelta(0) <= age < datetime.timedelta(hours=1)
    assert md.copyright.startswith("Copyright (c) 2026 the feeddrive maintainers")
    assert "Modelica Association Project" in md.copyright
    assert md.license.startswith("MIT") and "BSD-2-Clause" in md.license
    with zipfile.ZipFile(path) as zf:
        names = set(zf.namelist())
        licences = {n for n in names if n.startswith("documentation/licenses/")}
        assert licences == {"documentation/licenses/license.txt",
                            "documentation/licenses/feeddrive-MIT.txt",
                            "documentation/licenses/FMI-headers-BSD-2-Clause.txt"}
        mit = zf.read("documentation/licenses/feeddrive-MIT.txt").decode()
        bsd = zf.read("documentation/licenses/FMI-headers-BSD-2-Clause.txt").decode()
        header = zf.read(f"sources/fmi{fmi}Functions.h").decode()
    assert mit == (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert "2-Clause BSD License" in header and f"fmi{fmi}Functions.h" in bsd
    body = " ".join(header.split("Redistribution and use", 1)[1].split("----", 1)[0].split())
    assert body in " ".join(bsd.split())  # the header's own licence terms, word for word


def test_source_date_epoch_fixes_the_generation_time(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    from fmpy import read_model_description

    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    path = tmp_path / "lm.fmu"
    export_fmu(preset("linear-motor-example"), "linear-motor", path)
    assert read_model_description(str(path)).generationDateAndTime == "2023-11-14T22:13:20Z"


def test_an_export_says_what_of_the_solver_table_it_does_not_take(tmp_path: Path) -> None:
    """A ``[solver]`` table's method, output interval (and Rosenbrock method, step limit) have
    no counterpart in an FMU (its DOPRI5; the importer's communication points): the export
    said nothing and a user took them as applied (an outside check).  Its ``max_step`` is the
    embedded solver's ``solver.max_step``: now taken as its start value."""
    from typer.testing import CliRunner

    from feeddrive.cli import app
    from feeddrive.fmu import settings_not_taken

    path = tmp_path / "fmus.toml"
    path.write_text('extends = "wang2021"\n[solver]\nmethod = "rodas4"\nmax_step = 1e-4\n'
                    'output_interval = 0.0005\n', encoding="utf-8")
    params = fd.load(path)
    said = settings_not_taken(params)
    assert [s.split(" =")[0] for s in said] == ["method", "output_interval"]
    assert all("[solver] in" in s and "fmus.toml" in s for s in said)
    assert solver_starts(params, 0.0, 0.0)["solver.max_step"] == 1e-4
    assert "solver.max_step" not in solver_starts(preset("wang2021"), 0.0, 0.0)
    assert settings_not_taken(preset("wang2021")) == ()
    assert settings_not_taken(preset("wang2021"), fd.SolverOptions(method="dopri5")) == ()
    out = tmp_path / "x.fmu"
    result = CliRunner().invoke(app, ["export", "fmu", "--drive", "cdfs", "--params", str(path),
                                      "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    notes = [line for line in result.output.splitlines() if line.startswith("note:")]
    assert len(notes) == 1 and "method = rodas4" in notes[0] and "output_interval" in notes[0]


def test_the_help_names_what_an_export_does_not_take() -> None:
    """``export fmu --help`` said nothing of the settings it does not take (session 21's
    note): every name of :data:`feeddrive.fmu.NOT_TAKEN` is in it, and what it takes."""
    from typer.testing import CliRunner

    from feeddrive.cli import app
    from feeddrive.fmu import NOT_TAKEN

    result = CliRunner().invoke(app, ["export", "fmu", "--help"], terminal_width=200)
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    sentence = next(part for part in text.split(";") if "are not taken" in part)
    assert all(name in sentence for name in NOT_TAKEN), sentence
    assert "embedded DOPRI5" in text and "solver.max_step" in text
