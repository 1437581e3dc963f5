"""``experiments.mediapipe_3d``'s pieces: the placed pose proposed at the lifter's neck, and its
score term equal to the library's (:mod:`mocap.track.world`) on the same placed pose.

References: the lifter's most probable hypothesis (the proposal's neck must be its neck), the
library's :class:`~mocap.track.world.PlacedWorld` (the experiment's term must be its energy).
"""
from __future__ import annotations

import numpy as np
import pytest

from mocap.track.proposals import ProposalContext
from mocap.track.world import PlacedWorld, about_shoulders
from tests.track.test_lifter_in_tracker import MODEL, reaching_pose

m3d = pytest.importorskip("experiments.mediapipe_3d")


class _Lifted:
    def __init__(self, poses):
        self.poses = poses


def test_the_placed_pose_is_proposed_at_the_lifters_neck_and_the_term_is_the_librarys():
    truth = reaching_pose()
    placed = truth.copy()
    placed[:3] = (5.0, -3.0, 9.0)                            # MediaPipe's origin: anywhere
    anchor = truth.copy()
    anchor[:3] += (0.1, 0.05, 0.3)
    source = m3d.PlacedSource([placed, None], MODEL)
    (proposal,) = source.propose(None, ProposalContext(lifted=_Lifted(anchor[None])))
    np.testing.assert_allclose(MODEL.joint_positions(proposal.pose)[1], MODEL.joint_positions(anchor)[1], atol=1e-12)
    np.testing.assert_array_equal(proposal.pose[3:], placed[3:])
    assert source.propose(None, ProposalContext()) == []                      # no keypoints: nothing
    source.frame = 1
    assert source.propose(None, ProposalContext(lifted=_Lifted(anchor[None]))) == []    # no fit: nothing
    joints = MODEL.joint_positions(truth)
    joints[4] += (0.0, 0.0, 0.15)
    library = PlacedWorld(pose=placed, arms=about_shoulders(MODEL.joint_positions(placed)))
    target = m3d.about_shoulders(MODEL.joint_positions(placed))
    d2 = np.sum((m3d.about_shoulders(joints) - target) ** 2, axis=1) / m3d.SIGMA_M ** 2
    assert 0.5 * np.minimum(d2, m3d.CAP).sum() == pytest.approx(library.energy(joints), rel=1e-12)
