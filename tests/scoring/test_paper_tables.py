"""Tables 3-4 scored as the paper scores (lanekeep/scoring/paper_tables.py): at the car, over
every step, with the value the loop carries where a column has none."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lanekeep.scoring.paper_tables import PaperTrace, carried, paper_row, rmse_cm


def test_a_missing_value_is_carried_from_the_last_one():
    np.testing.assert_array_equal(carried([None, 0.1, None, float("nan"), 0.3]),
                                  [np.nan, 0.1, 0.1, 0.1, 0.3])
    assert math.isnan(rmse_cm(np.array([np.nan]), np.array([0.0])))


def test_a_model_that_fails_is_scored_on_the_value_it_left_behind():
    """Model #1 reads 10 cm off, then nothing for three steps while the car moves 30 cm:
    the paper's loop carries its last value, so those steps count with their real error,
    where ours (valid steps only) would not count them at all."""
    trace = PaperTrace()
    truth = [0.0, 0.0, 0.1, 0.2, 0.3]
    model1 = [0.1, 0.1, None, None, None]
    for k, t in enumerate(truth):
        trace.add(t, {"model1": model1[k], "model2": t, "final": t, "observer": None},
                  selected=1, in_event=k >= 2)
    row = paper_row(trace)
    expected = 100.0 * np.sqrt(np.mean(np.square([0.1, 0.1, 0.0, -0.1, -0.2])))
    assert row.rmse_cm["model1"] == pytest.approx(expected)
    assert row.rmse_cm["model2"] == 0.0
    assert math.isnan(row.rmse_cm["observer"]) and row.uncarried_steps["observer"] == 5
    assert row.event_steps == 3
    assert row.event_rmse_cm["model1"] == pytest.approx(100.0 * np.sqrt((0.0 + 0.01 + 0.04) / 3))
    assert row.selected_share_in_event == (0.0, 1.0)
    # Where a model had a value of its own (case 1's "loses the lane"): model #1 none of the
    # three event steps, both of the two others; a carried value is not its own.
    assert row.valid_share_in_event == (0.0, 1.0)
    assert row.valid_share_outside == (1.0, 1.0)
