"""The proposal gate (issue 50 item 6): a proposal is refined only when its unrefined score comes
within ``proposal_gate`` nats of the beam leader's pose, unrefined on the same frame.

Reference: the same tracker with the gate off (``proposal_gate=None``), whose candidates are
the gated tracker's plus the refinements the gate skipped, bit for bit; and the proposals' own
unrefined scores, each from one evaluation of every cost (:meth:`Tracker._rough_unary`)."""
from dataclasses import replace

import numpy as np
import pytest

from mocap.body import PARAMETER_INDEX as P
from mocap.track import Tracker, TrackerConfig
from mocap.track.proposals import Proposal
from tests.track.test_heading import CAMERA, MODEL, clip, turning

GATED = TrackerConfig(lag=0, evaluations=100, hypothesis_evaluations=30, jump_evaluations=20, proposals_refined=2,
                      proposal_evaluations=30, proposal_gate=5.0)


class NearAndFar:
    """Proposes the true pose and one far from it (moved 0.3 m sideways, the right arm swung
    down): the far one's unrefined score is tens of nats above the leader's."""

    origin = "near-far"

    def __init__(self, truth) -> None:
        self.truth = np.asarray(truth)

    def propose(self, prepared, context):
        far = self.truth.copy()
        far[P["root_x"]] += 0.3
        far[P["r_shoulder_flex"]] = 0.0
        return [Proposal(far, self.origin), Proposal(self.truth.copy(), self.origin)]


def candidates(config: TrackerConfig):
    truth = turning(1, start_deg=0.0)[0]
    frames, keypoints = clip([truth])
    tracker = Tracker(MODEL, CAMERA, config, truth, sources=[NearAndFar(truth)])
    tracker.push(0, frames[0], keypoints[0])
    return tracker, [c for c in tracker.scored if c.origin == NearAndFar.origin]


def test_only_proposals_near_the_leaders_pose_are_refined():
    ungated_tracker, ungated = candidates(replace(GATED, proposal_gate=None))
    gated_tracker, gated = candidates(GATED)
    assert len(ungated) == 2 and len(gated) == 1
    # the one kept is the refinement of the true pose, the same as the ungated tracker's, bit for bit
    near = [c for c in ungated if np.array_equal(c.pose, gated[0].pose)]
    assert len(near) == 1 and near[0].unary == gated[0].unary
    # every other candidate is the same too
    others = [(c.origin, c.pose.tobytes()) for c in gated_tracker.scored if c.origin != NearAndFar.origin]
    assert others == [(c.origin, c.pose.tobytes()) for c in ungated_tracker.scored if c.origin != NearAndFar.origin]


@pytest.mark.parametrize("gate, refined", [(1e9, 2), (-1e9, 0)])
def test_a_gate_past_every_score_refines_all_or_none(gate, refined):
    assert len(candidates(replace(GATED, proposal_gate=gate))[1]) == refined


@pytest.mark.parametrize("gate", [float("inf"), float("nan"), True, "5"])
def test_a_gate_must_be_a_finite_number_or_none(gate):
    with pytest.raises(ValueError, match="proposal_gate"):
        TrackerConfig(proposal_gate=gate)
