"""``python -m experiments.fit_score``: the tracker's score weights fitted on recorded candidates.

The tracker scores every candidate of a frame (the beam's hypotheses extended, recovery,
re-acquisition, jumps and the lifter's refined proposals) by a weighted sum of the terms of
:data:`mocap.track.score.TERMS` (:class:`mocap.track.ScoredCandidate`): F, the edge distance,
the keypoint distance, the pose prior's and the lifter's energies, and the motion term from the
previous frame. The weights were chosen by hand. One module per subcommand:

``record`` (:mod:`~experiments.fit_score.record`)
    Tracks benchmark sequences with oracle keypoints (or ``--no-keypoints``) and writes every
    frame's candidates with each term's value and their error against the truth, one ``.npz``
    per (sequence, seed) under ``--out`` (default ``experiments/results/fit_score``, git-ignored).
``fit`` (:mod:`~experiments.fit_score.fit`)
    Fits the weights on the records by a conditional logit, compares the fitted and the default
    weights' choices on held-out frames, and writes (``--write``) a
    :class:`~mocap.track.TrackerConfig` JSON.
``decompose`` (:mod:`~experiments.fit_score.decompose`)
    Splits each record's failing frames into where they are lost: lifter, refinement, score, decoder.
``decode`` (:mod:`~experiments.fit_score.decode`)
    An offline Viterbi through every recorded candidate at several motion weights, caps and lifter
    weights, against the tracker's own decisions.
``depth`` (:mod:`~experiments.fit_score.depth`)
    The decided poses moved along the neck's ray to a median depth over frames, and the true
    depth's bound.

What they share (the records, :class:`Candidates`, what a weight vector chooses) is
:mod:`~experiments.fit_score.candidates`; the command line is :mod:`~experiments.fit_score.cli`.
The fit chooses per frame with the motion from the previous frame's best-path hypothesis; the
tracker decodes paths (``lag`` frames later), and the refinements change with the keypoint
weight. So the fitted weights are confirmed by full tracking runs on a seed never used.
"""
from __future__ import annotations

from experiments.fit_score.candidates import (K_SAVED, MIN_SPREAD_MM, TERMS, Candidates, Choice, choose,
                                              default_weights, informative, load_records, record_path, scores)
from experiments.fit_score.decode import decode_offline
from experiments.fit_score.decompose import Remains, decompose, score_miss_frames
from experiments.fit_score.depth import smooth_depth
from experiments.fit_score.fit import (RIDGE, TEMPERATURE_MM, fit_weights, in_tracker_units, keep_unseen,
                                       tracker_config)
from experiments.fit_score.record import record_sequence

__all__ = ["K_SAVED", "MIN_SPREAD_MM", "RIDGE", "TEMPERATURE_MM", "TERMS", "Candidates", "Choice", "Remains",
           "choose", "decode_offline", "decompose", "default_weights", "fit_weights", "in_tracker_units",
           "informative", "keep_unseen", "load_records", "record_path", "record_sequence", "score_miss_frames",
           "scores", "smooth_depth", "tracker_config"]
