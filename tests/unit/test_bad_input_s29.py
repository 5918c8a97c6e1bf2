"""Library-level findings of the bad-input sweep of session 29: each was taken without a word
(a worker count dropped, a setting the quantity never reads, a resting table judged, one
trace counted twice) and is now one refusal naming what was given and what was expected."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from feeddrive.sweep.executors import check_executor


@pytest.mark.parametrize("kw", [{"workers": 2, "dask_workers": 2},
                                {"workers": 2, "scheduler": "tcp://127.0.0.1:1"}])
def test_a_local_pool_size_beside_dask_is_refused(kw: dict[str, Any]) -> None:
    """``--workers 2 --dask-workers 2`` ran on Dask and dropped ``--workers``."""
    other = "--dask-workers" if "dask_workers" in kw else "--scheduler"
    with pytest.raises(ValueError, match=f"--workers = 2 and {other}: give one, not both"):
        check_executor(**kw)


@pytest.mark.parametrize("held_at", [0.0, 0.005, 0.1234567, 0.8])
def test_a_table_at_rest_is_not_judged(held_at: float) -> None:
    """A trace of a table held still (at 5 mm: its fitted slope -7.7e-16 mm/s, the rounding
    of the fit's sums) was judged against that "command": UNSTABLE, ripple ratio 1.24e+04."""
    from feeddrive.analysis.trace import analyze_trace

    t = np.arange(3000) * 1e-3
    with pytest.raises(ValueError, match=r"^still\.csv: no moving segment to analyse \(the "
                                         r"table does not move\)$"):
        analyze_trace(t, np.full(t.size, held_at), source="still.csv")


def test_a_slow_table_still_moves() -> None:
    from feeddrive.analysis.trace import analyze_trace

    t = np.arange(3000) * 1e-3
    result = analyze_trace(t, 0.8 + 1e-6 * t, source="slow.csv")  # 1 µm/s at 800 mm
    assert [round(s.command_speed, 12) for s in result.segments] == [1e-6]


def _record(source: str, speed: float = 1e-3) -> Any:
    from feeddrive.analysis.fit import Experiment

    t = np.arange(0.0, 1.0, 1e-3)
    v = np.full(t.size, speed)
    return Experiment(source=source, time=t, signals={"table_position": v * t},
                      reference_time=t, table_speed=v, noise={"table_position": 1e-8})


@pytest.mark.parametrize(("second", "says"), [
    ("a.csv", "a.csv: given twice; each record counts once in a fit"),
    ("copy.csv", "copy.csv: the same record as a.csv; each record counts once in a fit"),
])
def test_a_fit_refuses_one_record_given_twice(monkeypatch: pytest.MonkeyPatch, second: str,
                                              says: str) -> None:
    """`feeddrive fit a.csv a.csv` fitted the record twice: its residuals weighed double and
    its standard errors came out 1/√2 of its own.  Refused before any simulation."""
    import feeddrive as fd
    from feeddrive.analysis import fit
    from feeddrive.engine import simulate as engine

    def no_run(*_a: Any, **_k: Any) -> Any:
        raise AssertionError("a simulation started although the input was refused")

    monkeypatch.setattr(engine, "simulate", no_run)
    with pytest.raises(fit.FitError, match=f"^{says}"):
        fit.fit_drive(fd.preset("wang2021"), [_record("a.csv"), _record(second)],
                      ["controller.velocity_integral_gain"])
    # two records of one rig are two records
    assert not fit._same_record(_record("a.csv"), _record("b.csv", speed=2e-3))


def test_a_percentiles_interval_is_not_claimed_beyond_the_draws() -> None:
    """`predict --samples 1` printed "95 %: 1.560 mm/s (Monte Carlo 95 % interval 1.560 …
    1.560)": an end the draws cannot bound was the extreme draw.  It is said so now."""
    from feeddrive.analysis.predict import _percentile

    one = [_percentile(np.array([1.56e-3]), q).to_dict()["mc_interval_mm_s"] for q in (5, 50, 95)]
    assert one == [["below the smallest draw", "above the largest draw"]] * 3
    # the 5 % point's lower end needs 72 draws (0.95^n < 0.025); 71 leave it unbounded
    x = np.linspace(1e-3, 2e-3, 71)
    assert _percentile(x, 5).to_dict()["mc_interval_mm_s"][0] == "below the smallest draw"
    assert _percentile(x, 95).to_dict()["mc_interval_mm_s"][1] == "above the largest draw"
    x = np.linspace(1e-3, 2e-3, 72)
    assert _percentile(x, 5).to_dict()["mc_interval_mm_s"][0] == pytest.approx(1.0)
    assert _percentile(x, 95).to_dict()["mc_interval_mm_s"][1] == pytest.approx(2.0)
    # every draw failed: no critical speed, not "above range"
    assert _percentile(np.full(3, np.nan), 50).to_dict()["critical_speed_mm_s"] == \
        "no draw found one"
