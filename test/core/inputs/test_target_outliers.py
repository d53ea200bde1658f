"""A target's failed readings: spikes found against hand-made logs, drifts and steps spared."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.inputs.target_outliers import (SPIKE_HALF_WINDOW, SPIKE_SIGMAS,
                                                         target_spikes)


def _drift(n: int = 800, seed: int = 0) -> np.ndarray:
    """A warm-up drift of 100 um with 0.3 um noise, and a re-zeroed instrument (+50 um that
    stays) half-way."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    y = 100.0 * np.tanh(k / 250.0) + rng.normal(0.0, 0.3, n)
    y[n // 2:] += 50.0
    return y


def test_a_drift_and_a_step_that_stays_are_no_spikes():
    spikes = target_spikes(_drift())
    assert spikes.count == 0
    # A drift far faster than the noise: each row moves 40 noises, still no spike.
    assert target_spikes(np.arange(300) * 12.0 + np.random.default_rng(1).normal(0, 0.3, 300)
                         ).count == 0


def test_failed_readings_of_one_to_three_rows_are_found_with_their_offsets():
    y = _drift()
    bad = {100: 4300.0, 101: 4300.0, 350: -200.0, 600: 30.0, 601: 30.0, 602: 30.0}
    for row, offset in bad.items():
        y[row] += offset
    spikes = target_spikes(y)
    assert np.flatnonzero(spikes.rows).tolist() == sorted(bad)
    # Each offset from the nearer side's median: the offset added, within the drift over
    # the window and the noise.
    np.testing.assert_allclose(spikes.offsets, [bad[r] for r in sorted(bad)], atol=2.0)
    assert spikes.noise == pytest.approx(0.3, rel=0.15)


def test_the_threshold_is_the_larger_of_noise_and_resolution():
    """A quantised target (2.5 um steps) whose differences are mostly zero reads a noise of
    0: the resolution sets the threshold, so one step is no spike, 30 steps and one more
    are."""
    y = np.round(_drift() / 2.5) * 2.5
    y[[200, 500]] += [2.5, (SPIKE_SIGMAS + 1) * 2.5]
    spikes = target_spikes(y)
    assert np.flatnonzero(spikes.rows).tolist() == [500]
    assert spikes.resolution == 2.5
    assert "its resolution 2.5 um" in spikes.text("z_um", "um")


def test_the_text_names_the_file_rows_and_what_was_done():
    y = _drift()
    y[[10, 11, 300]] += 1000.0
    text = target_spikes(y).text("d_um", "um", data_rows=np.arange(y.size) + 5)
    assert text.startswith("target d_um: 3 readings far from")
    assert "at data rows 15-16, 305" in text and "those rows left out" in text
    assert "up to +100" in text and "beyond the nearer side's median" in text


def test_too_few_readings_or_a_flat_target_find_nothing():
    assert target_spikes(np.arange(2 * SPIKE_HALF_WINDOW, dtype=float)).count == 0
    assert target_spikes(np.full(50, 3.0)).count == 0
    y = _drift(100)
    y[[20, 50]] = np.nan
    y[70] += 500.0
    assert np.flatnonzero(target_spikes(y).rows).tolist() == [70]


def test_each_run_is_judged_alone_so_a_zeroed_gauges_morning_ramp_is_no_spike():
    """Two days, the gauge zeroed each morning: day 1 ends at +73 um, day 2 starts at 0 and
    climbs 6.6 um a reading. Judged run by run the morning's readings have neighbours on
    one side only; a failed reading inside day 2 is still found."""
    rng = np.random.default_rng(2)
    k = np.arange(300)
    day = 75.0 * (1.0 - np.exp(-k / 12.0)) + rng.normal(0.0, 0.28, k.size)
    values = np.concatenate([day, day])
    values[450] += 40.0
    starts = np.zeros(values.size, dtype=bool)
    starts[[0, 300]] = True
    assert np.flatnonzero(target_spikes(values, starts).rows).tolist() == [450]


def test_a_thermal_peak_on_a_low_noise_gauge_is_no_spike():
    """A spindle burst of 6 rows seen through a 5-row lag: a 21 um peak on a 0.02 um gauge
    rises and falls over several steps alike (no step into it stands alone), and the
    spindle's speed moves on the same rows: the machine, not a failed reading."""
    rng = np.random.default_rng(4)
    n = 300
    speed = np.zeros(n)
    speed[150:156] = 8000.0
    drive = speed / 8000.0
    lagged = np.zeros(n)
    for k in range(1, n):
        lagged[k] = lagged[k - 1] + (drive[k] - lagged[k - 1]) / 5.0
    y = 30.0 * lagged + rng.normal(0.0, 0.02, n)
    assert target_spikes(y).count == 0
    assert target_spikes(y, inputs=[speed]).count == 0
    # Sampled coarsely the same burst is two readings out and back: only the speed that
    # moves with it tells the machine from a failed reading.
    coarse = np.zeros(60)
    coarse[30:32] = 38.0
    coarse += rng.normal(0.0, 0.2, 60)
    coarse_speed = np.where((np.arange(60) >= 30) & (np.arange(60) < 32), 8000.0, 0.0)
    assert np.flatnonzero(target_spikes(coarse).rows).tolist() == [30, 31]
    assert target_spikes(coarse, inputs=[coarse_speed]).count == 0


def test_a_failure_of_four_or_five_readings_is_left_out_whole():
    for width in (4, 5):
        y = _drift()
        y[200:200 + width] += 500.0
        assert np.flatnonzero(target_spikes(y).rows).tolist() == list(range(200, 200 + width))


def test_a_run_in_other_units_is_judged_by_its_own_noise():
    """A run logged in nm among um runs: its noise is its own, so it holds no spikes (the
    unit check names it), and a failed reading in a um run is still found."""
    rng = np.random.default_rng(6)
    runs = [10.0 * (1 - np.exp(-np.arange(120) / 30.0)) + rng.normal(0, 0.05, 120)
            for _ in range(3)]
    runs[1] = runs[1] * 1000.0
    runs[2][60] += 40.0
    values = np.concatenate(runs)
    starts = np.zeros(values.size, dtype=bool)
    starts[[0, 120, 240]] = True
    assert np.flatnonzero(target_spikes(values, starts).rows).tolist() == [300]


def test_short_runs_are_not_judged_and_do_not_fail():
    for n in (8, 10):
        y = np.zeros(n)
        y[n // 2] = 100.0
        assert target_spikes(y).count == 0          # 2 x 5 + 1 readings needed
    y = np.zeros(11) + np.random.default_rng(1).normal(0, 0.1, 11)
    y[5] = 100.0
    assert np.flatnonzero(target_spikes(y).rows).tolist() == [5]
