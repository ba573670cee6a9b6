"""The seed 004 experiment: registered, quick, and its figures consistent with the analytic steady error."""

import pytest

from groundstation import experiments


@pytest.fixture(scope="module")
def result():
    return experiments.load("seed004").run(quick=True)


def test_fused_estimates_beat_the_raw_aids_and_dead_reckoning_diverges(result):
    fluct = result.tables[0]
    rows = {(r[0], r[1], r[2]): r for r in fluct.rows}
    for profile in ("hover", "flight"):
        raw = rows[(profile, "-", "raw baro / GPS")]
        for attitude in ("truth", "ahf"):
            for label in ("single channel", "dual channel", "dual + GPS velocity"):
                fused = rows[(profile, attitude, label)]
                assert fused[3] < 0.5 * raw[3] and fused[4] < 0.7 * raw[4]
            assert rows[(profile, attitude, "accelerometer only")][4] > 3 * raw[4]


def test_steady_error_table_matches_b_over_kv(result):
    single, dual = result.tables[1].rows
    assert single[1] == pytest.approx(single[2], rel=0.1)  # b / kv, less the fraction kp Δ taken at readings
    assert abs(dual[1]) < 0.1 * single[2]


def test_figures_have_truth_raw_and_fused(result):
    for fig in result.figures:
        labels = [s.label for s in fig.series]
        assert labels[0] == "truth" and "single channel" in labels and "dual channel" in labels
        assert all(len(s.x) == len(s.y) > 0 for s in fig.series)
