"""What a notebook shows for the public results (2026-12-06): one line of what the object is,
with its numbers in the CLI's units and where the rest is — not the dataclass dump of every
array (a ``LoopAnalysis`` printed 46 kB, a ``DriveSystem`` its whole parameter set, 3.3 kB).

The numbers a repr shows are the object's own, read back here from its fields."""

from __future__ import annotations

import pytest

import feeddrive as fd
from feeddrive.parameters import ParameterError

LONGEST = 400  # [characters] a repr that fits a notebook cell's line or two


@pytest.fixture(scope="module")
def system() -> fd.DriveSystem:
    return fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)


def _short(text: str) -> str:
    assert "\n" not in text and len(text) <= LONGEST, (len(text), text[:200])
    return text


def test_a_drive_system_names_its_set_instead_of_printing_it(system: fd.DriveSystem) -> None:
    assert _short(repr(system)) == ("DriveSystem(parameters=<DriveParameters 'wang2021'>, "
                                    "drive='cdfs', table_position=0.4, nut_hold='locked')")
    started = fd.DriveSystem(system.parameters, "ddfs", 0.3, initial_state={"table_speed": 1e-3})
    assert repr(started).endswith("initial_state={'table_speed': 0.001})")
    text = _short(repr(system.parameters))
    assert text.startswith("<feeddrive DriveParameters 'wang2021': Wang2021 with the default")
    assert "sections screw, coupling," in text and "dumps(p)" in text


def test_the_linear_results_state_their_numbers_in_mm_s_and_hz(system: fd.DriveSystem) -> None:
    band = fd.stability_band(system)
    (lo, hi), = band.intervals
    text = _short(repr(band))
    # Wang2021 CDFS at mid-screw: unstable 0.17–1.40 mm/s (stability_band's docstring)
    assert f"unstable {1e3 * lo:.3f}–{1e3 * hi:.3f} mm/s" in text
    assert round(1e3 * lo, 2) == 0.17 and round(1e3 * hi, 2) == 1.40
    assert f"(mode {band.mode_frequency_hz[0]:.3g} Hz)" in text
    assert f"{band.speeds.size} speeds" in text

    loops = fd.loop_analysis(system, 1.5e-3)
    text = _short(repr(loops))
    p = loops.dominant()
    assert f"least-damped mode {p.frequency_hz:.4g} Hz, ζ {p.damping_ratio:.3g}" in text
    for loop in loops.loops:
        assert loop.name in text and f"PM {loop.phase_margin_deg:.3g}°" in text
    assert _short(repr(loops.linear)).startswith(
        f"<feeddrive LinearModel: {len(loops.linear.states)} states")

    response = fd.frequency_response(system, "tracking")
    assert "200 frequencies 0.1–1000 Hz" in _short(repr(response))


def test_a_critical_speed_search_reads_as_the_cli_prints_it(system: fd.DriveSystem) -> None:
    search = fd.critical_speed_from_rest(system, speed_range=(1.3e-3, 1.8e-3),
                                         coarse_step=0.2e-3, resolution=0.05e-3)
    text = _short(repr(search))
    assert search.display() in text and f"{len(search.trials)} trials" in text


def test_a_speed_passed_where_a_response_name_goes_is_refused(system: fd.DriveSystem) -> None:
    """``loop_analysis(system, 1.5e-3)`` takes the speed second; ``frequency_response`` takes
    the response's name there, and a float used to end in an AttributeError inside it."""
    with pytest.raises(ParameterError, match=r"^input = 0.0015: expected a name .*table_speed="):
        fd.frequency_response(system, 1.5e-3)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"^output = 3: expected None or the name"):
        fd.frequency_response(system, "load_force", 3)  # type: ignore[arg-type]


@pytest.mark.parametrize("speed", ["1", None, True, float("nan")])
def test_a_speed_that_is_not_a_number_is_refused_naming_the_field(system: fd.DriveSystem,
                                                                   speed: object) -> None:
    """``loop_analysis(system, "1")`` ended in ``TypeError: must be real number, not str``
    from inside the profile's check (2026-12-06); then it was refused as
    ``profile.table_speed``, a name the caller never wrote (2026-12-07): the argument is
    named."""
    with pytest.raises(ParameterError, match=r"^table_speed = .*: expected a finite "
                                             r"speed \[m/s\]$"):
        fd.loop_analysis(system, speed)  # type: ignore[arg-type]


def test_a_new_users_first_mistakes_are_named(system: fd.DriveSystem) -> None:
    """A parameter set where the drive goes, a dict where SolverOptions go, a signal name that
    is not there: each ended in an AttributeError or a bare KeyError (2026-12-06)."""
    params = system.parameters
    with pytest.raises(ParameterError, match=r"^system = 'DriveParameters': expected a "
                                             r"DriveSystem, e\.g\. DriveSystem\(params"):
        fd.simulate(params, fd.ConstantSpeed(1e-3), 0.1)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"^options = 'dict': expected SolverOptions"):
        fd.simulate(system, fd.ConstantSpeed(1e-3), 0.1,
                    options={"rtol": 1e-8})  # type: ignore[arg-type]
    result = fd.simulate(system, fd.ConstantSpeed(1e-3), 0.1)
    with pytest.raises(KeyError, match=r"'nope': no such signal in this run; its signals: "
                                       r"screw_angle, "):
        result["nope"]
    # every listed name is readable, the derived and following-error signals too
    assert all(result[name].shape == result.time.shape for name in result.signal_names())


def test_a_short_sine_run_is_titled_with_its_amplitude(system: fd.DriveSystem) -> None:
    """A 0.1-s run of a 1-mm/s, 0.2-Hz sine reaches 0.125 mm/s; its title said "sine amplitude
    0.1253 mm/s" (the largest reference reached) before 2026-12-06."""
    short = fd.simulate(system, fd.SineSpeed(1e-3), 0.1)
    assert float(abs(short["table_speed_reference"]).max()) < 0.13e-3
    assert "sine amplitude 1 mm/s, position 400 mm, 0.1 s" in repr(short)
