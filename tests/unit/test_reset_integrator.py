"""The reset integrator (issue 37 item 4; Beerens et al., Automatica 2019): the sampled
velocity loop's integral reset at the zero crossings of the quantised position error."""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.model.positioning_profile import stops_profile
from feeddrive.parameters import ParameterError, loads

# wang2021-drive: 8/4/2-kHz sampled loops and a 0.05-µm table scale (its DRIVE_ASSUMPTIONS);
# a stiffer position loop and integral than its defaults so the 10-µm move overshoots
DRIVE = """extends = "wang2021-drive"
name = "reset"
[controller]
position_gain = 30.0
velocity_integral_gain = 15000.0
"""
PROFILE, _ = stops_profile([10e-6], feed=1e-3, acceleration=0.1, dwell=0.6)
OPTIONS = fd.SolverOptions(output_interval=1e-3)


def run(text: str) -> fd.Result:
    return fd.simulate(fd.DriveSystem(loads(text), "cdfs", 0.4), PROFILE, 0.6, options=OPTIONS)


def test_a_continuous_velocity_loop_is_refused():
    """The reset acts on the sampled loop's held integral; wang2021's loops are continuous."""
    text = 'extends = "wang2021"\nname = "c"\n[reset_integrator]\nfraction = 0.0\n'
    with pytest.raises(ParameterError) as err:
        run(text)
    assert err.value.field == "controller.velocity_period"


def test_an_unknown_axis_is_refused():
    with pytest.raises(ParameterError, match="reset_integrator.axis.*screw"):
        run(DRIVE + '[reset_integrator]\naxis = "spindle"\n')


@pytest.mark.slow  # three runs with their compilation: ≈ 30 s measured
def test_the_reset_changes_the_run_only_by_what_it_removes():
    """fraction = 1 keeps the whole integral: the run is the plain one to the last digit, while
    the crossings are still counted; fraction = 0 resets at the overshoot's crossings and
    changes the settling."""
    plain = run(DRIVE)
    kept = run(DRIVE + "[reset_integrator]\nfraction = 1.0\n")
    reset = run(DRIVE + "[reset_integrator]\nfraction = 0.0\n")
    x0 = np.asarray(plain["table_position"])
    assert np.array_equal(np.asarray(kept["table_position"]), x0)
    counts = np.asarray(reset["reset_integrator_count"])
    assert counts[-1] >= 1
    assert np.all(np.diff(counts) >= 0)
    # the first reset comes after the first crossing of the target (the overshoot)
    t = np.asarray(reset.time)
    x = np.asarray(reset["table_position"])
    first_reset = t[np.argmax(counts > 0)]
    first_crossing = t[np.argmax(x >= 10e-6)]
    assert first_reset >= first_crossing - 2e-3
    assert not np.array_equal(x, x0)


# --- the acceptance: a friction without presliding memory (the static Stribeck law,
# Armstrong-Hélouvry et al. 1994, the class of friction Beerens et al. analyse) on the
# wang2021-drive CDFS at its own gains (P position, PI velocity, 8/4/2-kHz loops, 0.05-µm
# scale), a 10-µm move
STRIBECK = """extends = "wang2021-drive"
name = "stribeck"
[friction.screw]
law = "stribeck"
{smoothing}[friction.guide]
law = "stribeck"
{smoothing}"""
COUNT = 5e-8  # [m] the scale's step, wang2021 DRIVE_ASSUMPTIONS
STEP = stops_profile([10e-6], feed=1e-3, acceleration=0.1, dwell=10.0)[0]


def _error_counts(text: str) -> tuple[np.ndarray, np.ndarray]:
    r = fd.simulate(fd.DriveSystem(loads(text), "cdfs", 0.4), STEP, 10.0,
                    options=fd.SolverOptions(output_interval=1e-3))
    t = np.asarray(r.time)
    return t, (np.asarray(r["table_position"]) - 10e-6) / COUNT


def test_the_reset_stops_the_hunting_of_a_static_stribeck_drive():
    """Smoothing speed v_ε = 10 µm/s: the plain loop hunts (measured: −113 … +136 counts from
    2 s, period 4.65 s, i.e. 0.215 Hz, over 2–30 s); with the reset (two resets) the table
    stays within one count from 2 s to 10 s (measured 0.1 … 0.4 counts)."""
    text = STRIBECK.format(smoothing="smoothing_velocity = 1e-5\n")
    t, plain = _error_counts(text)
    late = t >= 2.0
    assert np.ptp(plain[late]) >= 2.0
    up = np.flatnonzero((plain[late][:-1] < 0) & (plain[late][1:] >= 0))
    assert up.size >= 1  # it passes the target again: a cycle, not a slow approach
    t, reset = _error_counts(text + "[reset_integrator]\nfraction = 0.0\n")
    assert np.max(np.abs(reset[t >= 2.0])) <= 1.0


def test_the_reset_narrows_the_hunting_at_the_default_smoothing():
    """At the law's default v_ε = 1 µm/s the plain loop hunts more slowly (measured
    −57.9 … +59.4 counts over 2–30 s, period 10.1 s); the reset narrows the band from 2 s to
    10 s from 117 to 12.6 counts (measured) but does not hold one count (docs/extending.md)."""
    text = STRIBECK.format(smoothing="")
    t, plain = _error_counts(text)
    t, reset = _error_counts(text + "[reset_integrator]\nfraction = 0.0\n")
    late = t >= 2.0
    assert np.ptp(plain[late]) >= 2.0
    assert np.ptp(reset[late]) < 0.2 * np.ptp(plain[late])
