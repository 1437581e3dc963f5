"""``experiments.beam_origins``: each stage's share of the decided frames and of the budget, by
hand on made-up frames."""
from __future__ import annotations

import pytest

from experiments.beam_origins import candidate_budget, stage_shares, table
from mocap.track import TrackerConfig


def test_the_shares_and_budgets_of_made_up_frames():
    config = TrackerConfig(evaluations=500, hypothesis_evaluations=150, jump_evaluations=80, proposal_evaluations=100,
                           mirror_evaluations=0)
    frames = [["tracked", "tracked", "tracked", "jump", "jump", "mirror", "lifter", "lifter"],
              ["tracked", "tracked", "jump", "jump", "reacquisition", "lifter", "lifter"]]
    shares = {s.origin: s for s in stage_shares(["tracked", "lifter", "tracked", "jump"], frames, config)}
    # budgets by hand: frame 1 500 + 2 x 150 + 2 x 80 + 0 + 2 x 100; frame 2 500 + 150 + 160 + 150 + 200
    total = (500 + 300 + 160 + 0 + 200) + (500 + 150 + 160 + 150 + 200)
    assert shares["tracked"].chosen_rate == 0.5 and shares["lifter"].chosen_rate == 0.25
    assert shares["mirror"].chosen_rate == 0.0 and shares["mirror"].budget_per_frame == 0.0
    assert shares["tracked"].candidates_per_frame == 2.5
    assert shares["tracked"].budget_per_frame == pytest.approx((800 + 650) / 2)
    assert shares["jump"].budget_share == pytest.approx(320 / total)
    assert sum(s.budget_share for s in shares.values()) == pytest.approx(1.0)
    assert list(shares)[0] == "tracked"                      # the most chosen first
    assert "| lifter | 25.0 % | 2.00 | 200 |" in table({"frames": 4, "seeds": [0], "keypoints": "oracle",
                                                       "stages": [s.__dict__ for s in shares.values()]})


def test_an_unknown_stage_and_no_frames_are_refused():
    with pytest.raises(ValueError, match="origin"):
        candidate_budget("exemplars", 0, TrackerConfig())
    with pytest.raises(ValueError, match="no frame"):
        stage_shares([], [], TrackerConfig())
