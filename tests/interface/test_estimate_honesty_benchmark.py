"""benchmarks.estimate_honesty tables each point's error against a run at 8 times its steps
over 16/15 of its estimate, clear of the stops and with impacts apart."""

from __future__ import annotations

from benchmarks.estimate_honesty import lines_of, measure


def test_a_point_clear_of_the_stop_and_one_with_impacts_are_tabled_apart():
    # (at 235 Hz the swing stays 2 um clear of the stop: the automatic step, 704 a period,
    # is the contact's, and its runs take multi-steps)
    points = [dict(gap=2e-6, frequency=235.0), dict(gap=1e-6, frequency=140.0)]
    rows, worst = lines_of("two", measure("paper", points))
    assert [row.split("|")[2].strip() for row in rows] == ["clear of the stops",
                                                          "with impacts"]
    for row in rows:
        cells = [cell.strip() for cell in row.split("|")]
        assert cells[3] == "1"
        # (RK4's fourth order: each error about 16/15 of its estimate)
        assert 0.5 < float(cells[4]) < 2.0, row
    assert len(worst) == 2 and all(line.startswith("- two: gap ") for line in worst)
