"""Searches `reproduce` shares between studies instead of running them twice: the
model-reading study's shipped reading at mid-screw is Table 3's CDFS search and Fig. 8's
DDFS search, and the compensation study's uncompensated CDFS and its DDFS at 16 mm/s are
the same two searches; a shared row is what the study computes from that search."""

from __future__ import annotations

from typing import Any

import pytest

import feeddrive as fd
from feeddrive.reproduce import reading_study, runner
from feeddrive.reproduce.studies import MID, PAPER, StudySettings


def _paper_jobs(params: Any, settings: StudySettings) -> dict[str, Any]:
    jobs = {f"crit-cdfs-{a}": (params, "cdfs", a, 0.0, settings, "rest")
            for a in PAPER["positions"]}
    jobs.update({f"crit-ddfs-{a}": (params, "ddfs", a, PAPER["experiment_nut_speed"],
                                    settings, "rest") for a in PAPER["positions"]})
    jobs["crit-ddfs-fig8"] = (params, "ddfs", MID, PAPER["ddfs_sim_nut_speed"], settings,
                              "rest")
    jobs["crit-cdfs-running"] = (params, "cdfs", MID, 0.0, settings, "running")
    return jobs


def test_the_shipped_reading_shares_the_paper_searches() -> None:
    settings = StudySettings()
    jobs = _paper_jobs(fd.preset("wang2021"), settings)
    study = {f"study-{i}": job for i, job in enumerate(reading_study.jobs())}
    shared = runner._shared_rows(study, jobs)
    assert {study[k][0] for k in shared} == {"wang2021 (+ fitted velocity integral)"}
    assert sorted(shared.values()) == [f"crit-cdfs-{MID}", "crit-ddfs-fig8"]
    comp = runner._compensation_shares(fd.preset("wang2021"), settings, jobs)
    assert sorted(comp.values()) == [f"crit-cdfs-{MID}", "crit-ddfs-fig8"]
    # another parameter set shares nothing with the readings of the wang2021 presets
    other = _paper_jobs(fd.preset("wang2021").replace_path("table.mass", 100.0), settings)
    assert runner._shared_rows(study, other) == {}
    # nor a study on another grid with the compensation study's protocol grid
    assert runner._compensation_shares(fd.preset("wang2021"),
                                       StudySettings(coarse_step=1e-4), jobs) == {}


def test_a_shared_row_is_the_row_the_study_computes(monkeypatch: pytest.MonkeyPatch) -> None:
    search = {"critical_speed_mm_s": 1.56, "status": "found", "kind": "oscillation",
              "bands": [{"kind": "oscillation", "lower_mm_s": 1.2, "upper_mm_s": 1.55}],
              "trials": [], "simulated_time_s": 1.0}
    monkeypatch.setattr(reading_study, "critical_speed", lambda *a, **k: search)
    job = reading_study.jobs()[8]
    assert reading_study.run_variant(job) == reading_study.row_from_search(job, search)


def test_a_study_row_computed_without_the_estimate_is_the_row_of_a_search_with_it(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The model-reading study's searches carry no embedded error estimate (its rows state
    none): the row equals the one made from the same search with the estimate carried — as a
    row shared from a paper search is — since the estimate does not change the runs."""
    from feeddrive.reproduce import studies

    job = reading_study.jobs()[9]  # the shipped reading, DDFS at 16 mm/s
    p = reading_study.variant_parameters(job)
    with_estimate = studies.critical_speed(p, job[3], MID, job[4], StudySettings())
    assert any(t.get("speed_error_mm_s") is not None for t in with_estimate["trials"])
    carried: list[bool] = []
    search = studies.critical_speed

    def recording(*a: Any, **k: Any) -> Any:
        carried.append(k.get("error_estimate", True))
        return search(*a, **k)

    monkeypatch.setattr(reading_study, "critical_speed", recording)
    assert reading_study.run_variant(job) == reading_study.row_from_search(job, with_estimate)
    assert carried == [False]
