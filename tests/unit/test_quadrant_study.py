"""The report section "does the DDFS remove the quadrant glitch?" (issue 37 item 5): its
sentences carry the rows' numbers (what the rows come from is tested in
tests/unit/test_circular_run.py; the study itself runs in the reproduction,
tests/validation)."""

from __future__ import annotations

from feeddrive.analysis.circular_run import SETTLE_FRACTION
from feeddrive.reproduce.quadrant_study import CASES, section


def _row(case: str, drive: str, vn: float, spike: float, variant: bool,
         sites: list[str]) -> dict[str, object]:
    return {"case": case, "drive": drive, "nut_speed_mm_s": vn, "variant": variant,
            "spike_max_um": spike, "spike_mean_um": spike / 2,
            "bidirectional_circular_deviation_um": 100.0 + spike, "reversing_sites": sites}


def test_section_reads_its_answer_from_the_rows() -> None:
    rows = [_row("CDFS", "cdfs", 0.0, 50.0, False, ["screw", "guide"]),
            _row("DDFS, v_n = 20 mm/s", "ddfs", 20.0, 30.0, False, ["guide"]),
            _row("DDFS, v_n = 100 mm/s", "ddfs", 100.0, 20.0, False, ["guide"]),
            _row("DDFS, v_n = 20 mm/s, guide friction ×2", "ddfs", 20.0, 40.0, True,
                 ["guide"])]
    text, table = section({"radius_mm": 10.0, "feed_mm_min": 1000.0, "rows": rows})
    assert "Largest spike: CDFS 50 µm; DDFS 30 µm at v_n = 20 mm/s, 20 µm at v_n = 100 mm/s" \
        in text
    assert "at 100 mm/s the DDFS leaves 40% of the CDFS's largest spike" in text
    assert "Mean spike at v_n = 20 mm/s: 15 µm; guide friction ×2: 20 µm." in text
    assert [r["reverse"] for r in table] == ["screw, guide", "guide", "guide", "guide"]
    assert table[0]["G(b) [µm]"] == "150"
    assert table[0]["lead arc [°]"] == "—"  # a stored study from before the settling rule


def test_section_states_each_cases_lead_arc_and_the_rule() -> None:
    rows = [{**_row("CDFS", "cdfs", 0.0, 50.0, False, ["screw"]), "lead_arc_deg": 372.94},
            {**_row("DDFS, v_n = 20 mm/s", "ddfs", 20.0, 30.0, False, ["guide"]),
             "lead_arc_deg": 300.0}]
    text, table = section({"radius_mm": 10.0, "feed_mm_min": 1000.0, "rows": rows})
    assert [r["lead arc [°]"] for r in table] == ["372.9", "300"]
    assert f"has decayed to {SETTLE_FRACTION:.1%}" in text


def test_section_without_the_study_says_so() -> None:
    assert section(None) == ("Not run (`reproduce --no-study`).", [])


def test_cases_name_their_drive_and_nut_speed() -> None:
    for label, drive, nut_speed, _ in CASES:
        assert label.startswith(drive.upper())
        assert (f"v_n = {nut_speed * 1e3:g} mm/s" in label) == (nut_speed > 0)


def test_section_says_where_the_spikes_do_not_stand_out() -> None:
    """Where fewer than eight spikes stand out of the path's deviation before their
    reversal, the table says how many and the text says what such a spike is (session 25:
    at v_n = 10 mm/s six of eight did not, the path oscillating between the reversals)."""
    rows = [{**_row("CDFS", "cdfs", 0.0, 50.0, False, ["screw"]), "spikes_standing_out": 8},
            {**_row("DDFS, v_n = 10 mm/s", "ddfs", 10.0, 30.0, False, ["guide"]),
             "spikes_standing_out": 2}]
    text, table = section({"radius_mm": 10.0, "feed_mm_min": 1000.0, "rows": rows})
    assert [r["stand out"] for r in table] == ["8 of 8", "2 of 8"]
    assert "In 1 of the 2 cases (DDFS, v_n = 10 mm/s) fewer than the eight spikes" in text
    assert "that oscillation's largest excursion" in text
    # a stored study from before the column: a dash, no sentence
    text, table = section({"radius_mm": 10.0, "feed_mm_min": 1000.0,
                           "rows": [_row("CDFS", "cdfs", 0.0, 50.0, False, ["screw"]),
                                    _row("DDFS, v_n = 20 mm/s", "ddfs", 20.0, 30.0, False,
                                         ["guide"])]})
    assert table[0]["stand out"] == "—" and "fewer than the eight" not in text
