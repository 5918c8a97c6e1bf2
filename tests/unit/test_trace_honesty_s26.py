"""Session 26 (an outside check, 2026-12-07): what the creep analyses say about a record
that does not resolve, or has not settled into, what they measure."""

from __future__ import annotations

import numpy as np

from feeddrive.analysis.trace import analyze_trace

DT = 1e-3  # [s]


def _position(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Position [m] of the speed ``v`` [m/s] (trapezoidal integral)."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])


def _staircase(last_hold: str = "grows") -> tuple[np.ndarray, np.ndarray]:
    """Holds of 20 s at 1.5, 1.45 and 1.4 mm/s; the last one's 5-Hz ripple grows from 0 to
    ±90 % of the command between 4 and 12 s into it (smooth, then stick-slip-like)."""
    t_all, v_all, t0 = [], [], 0.0
    for k, c in enumerate((1.5e-3, 1.45e-3, 1.4e-3)):
        t = t0 + np.arange(20000) * DT
        v = np.full(t.size, c)
        if k == 2 and last_hold == "grows":
            amp = 0.9 * np.clip((t - t0 - 4.0) / 8.0, 0.0, 1.0)
            v = c * (1.0 + amp * np.sin(2 * np.pi * 5.0 * (t - t0)))
        t_all.append(t)
        v_all.append(v)
        t0 += 20.0
    t, v = np.concatenate(t_all), np.concatenate(v_all)
    return t, _position(t, v)


def test_one_hold_whose_ripple_grows_is_one_segment_full_and_decimated() -> None:
    # finding 2: the 1.4-mm/s hold was two segments (1.39993 "smooth", ripple 0.49, and
    # 1.39997 "creeping"): 7e-5 mm/s apart, under --min-step 0.005 mm/s
    t, x = _staircase()
    for k in (1, 5):
        a = analyze_trace(t[::k], x[::k])
        speeds = [round(1e3 * s.command_speed, 3) for s in a.segments]
        assert speeds == [1.5, 1.45, 1.4], (k, speeds)
        assert [s.metrics.verdict for s in a.segments] == ["smooth", "smooth", "creeping"]
        (c,) = a.critical
        assert c.monotonic
        assert round(1e3 * c.lowest_smooth, 3) == 1.45
        assert round(1e3 * c.first_creeping, 3) == 1.4
        assert not any("not sharp" in n for n in a.notes)


def test_a_hold_whose_oscillation_grows_is_not_settled_and_the_headline_not_firm() -> None:
    # finding 3: 4-s holds whose 5.45-Hz ripple grew 0.04 → 0.13 hold to hold were each
    # "smooth", the headline "lowest smooth 1.36 mm/s; first creeping none" with no word
    import re

    from feeddrive.analysis.trace import critical_of_holds, describe_critical

    t = np.arange(12000) * DT
    c = np.where(t < 4.0, 1.6e-3, np.where(t < 8.0, 1.5e-3, 1.4e-3))
    # the last hold: a 5.45-Hz ripple growing from 2 % to 13 % peak-to-peak of the command
    grow = np.where(t >= 8.0, 0.01 * np.exp((t - 8.0) * np.log(6.5) / 4.0), 0.0)
    v = c * (1.0 + grow * np.sin(2 * np.pi * 5.45 * t))
    a = analyze_trace(t, _position(t, v), command=c)
    assert [s.metrics.verdict for s in a.segments] == ["smooth"] * 3
    assert [s.settled for s in a.segments] == [True, True, False]
    (crit,) = a.critical
    assert [round(1e3 * s, 3) for s in crit.unsettled] == [1.4]
    assert any(re.match(r"segment 8\.\d\d–12\.00 s \(1\.4 mm/s\): smooth by the window rule "
                        r"but not settled", n) for n in a.notes)
    text = describe_critical(crit.lowest_smooth, crit.first_creeping, "hold",
                             unsettled=crit.unsettled)
    assert re.match(r"lowest smooth 1\.4 mm/s; first creeping none \(no hold creeps\) — not "
                    r"firm: the hold at 1\.4 mm/s is smooth by the window rule but not "
                    r"settled", text)
    # settled holds (or none given) leave the headline as it was
    assert critical_of_holds([(1.6e-3, False), (1.5e-3, False)])[0].unsettled == ()
    assert critical_of_holds([(1.6e-3, False, True), (1.5e-3, True, False)])[0].unsettled == ()


def _stick_slip(step: float, duration: float = 12.0) -> tuple[np.ndarray, np.ndarray]:
    """A 5.47-Hz stick-slip speed [m/s] about 1 mm/s sampled every ``step`` [s]: stuck for
    12.5 % of each period, then a sin² slip whose mean makes the command."""
    t = np.arange(0.0, duration, step)
    phase = (t * 5.47) % 1.0
    slip = np.clip((phase - 0.125) / 0.875, 0.0, 1.0)
    return t, 1e-3 / (0.875 * 0.5) * np.sin(np.pi * slip) ** 2


def test_the_stick_fraction_is_stable_where_resolved_and_flagged_where_not() -> None:
    # finding 1: 0.125 at 1 ms, 0.0903 at 20 ms, 0.0165 at 50 ms, with nothing said
    import re

    from feeddrive.analysis.creep_window import creep_metrics

    fine = creep_metrics(*_stick_slip(0.5e-3), 1e-3)
    resolved = creep_metrics(*_stick_slip(1e-3), 1e-3)
    coarse = creep_metrics(*_stick_slip(20e-3), 1e-3)
    assert fine.sampling_note is None and resolved.sampling_note is None
    assert f"{resolved.stick_fraction:.3g}" == f"{fine.stick_fraction:.3g}"
    assert abs(coarse.stick_fraction - fine.stick_fraction) > 0.01  # it moves …
    note = coarse.sampling_note  # … and says so
    assert note is not None
    assert re.match(r"stick fraction 0\.\d+ depends on the sampling "
                    r"\(20-ms step, 9\.1\d samples per 5\.47-Hz period\): 0\.\d+ from every "
                    r"second sample", note), note
    assert coarse.to_dict()["sampling_note"] == note


def test_what_the_speed_filter_takes_off_the_detected_ripple_is_said() -> None:
    # finding 4: the 20-ms window was justified at 2 Hz; at 5.47 Hz it moves the numbers
    import re

    from feeddrive.analysis.trace import savgol_gain

    t, v = _stick_slip(1e-3, duration=20.0)
    a = analyze_trace(t, _position(t, v), command_speed=1e-3)
    assert any(re.match(r"segment 0\.00–20\.00 s: the 21-ms speed filter passes 98\.\d % of "
                        r"the 5\.47-Hz ripple", n) for n in a.notes), a.notes
    # a 2-Hz ripple: the loss (0.17 %) is below the printed digits, nothing said
    t2 = np.arange(0.0, 20.0, 1e-3)
    x2 = 1e-3 * t2 - 0.8e-3 / (2 * np.pi * 2.0) * np.cos(2 * np.pi * 2.0 * t2)
    b = analyze_trace(t2, x2, command_speed=1e-3)
    assert not any("speed filter passes" in n for n in b.notes)
    assert savgol_gain(21, 1e-3, 2.0) > 0.99 > savgol_gain(21, 1e-3, 5.47) > 0.98
