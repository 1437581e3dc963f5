"""Tracking: one frame's two-step registration, hypothesis proposals, the beam and its decoder.

========================  ===============================================================
module                    what
========================  ===============================================================
``config``                :class:`TrackerConfig` (and :meth:`TrackerConfig.paper`), budget split
``registration``          :func:`register`: region step, then edge step (paper 3.2-3.3)
``proposals``             the proposal stage (sources: the lifter's), re-acquisition, kinematic jumps
``score``                 the score's terms in one table (:data:`~mocap.track.score.TERMS`), their
                          weights, the motion term, :class:`ScoredCandidate`
``decode``                Viterbi over each frame's hypotheses
``tracker``               :class:`Tracker`: the beam, streaming decisions, exact state
========================  ===============================================================
"""
from mocap.track.config import AUTO_SPLIT_THRESHOLD, EDGE_STARTS, TrackerConfig, split_budget
from mocap.track.decode import backtrack, viterbi, viterbi_step
from mocap.track.proposals import (LifterSource, Proposal, ProposalContext, ProposalSource, jump_proposals,
                                   reach_proposals, unexplained_hands)
from mocap.track.registration import Registration, register
from mocap.track.score import ScoredCandidate
from mocap.track.tracker import FrameResult, Tracker, proposal_sources, track_prepared

__all__ = ["AUTO_SPLIT_THRESHOLD", "EDGE_STARTS", "FrameResult", "LifterSource", "Proposal", "ProposalContext",
           "ProposalSource", "Registration", "ScoredCandidate", "Tracker", "TrackerConfig",
           "backtrack", "jump_proposals", "proposal_sources", "reach_proposals", "register", "split_budget", "track_prepared",
           "unexplained_hands", "viterbi", "viterbi_step"]
