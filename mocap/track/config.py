"""Settings of the tracker: one typed, JSON-backed configuration and the paper's method.

:class:`TrackerConfig` holds every option of the registration (the paper's two-step downhill
simplex, sections 3.2-3.3 and 5) and of what this toolkit adds beyond it: failure recovery,
hand re-acquisition, a beam of hypotheses with kinematic jumps, a learned pose prior in their
score, and temporal decoding. :meth:`TrackerConfig.paper` is the paper's method with every
addition off, as the experiments reproduce it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from mocap.body.pose import N_PARAMETERS
from mocap.config import JsonConfig
from mocap.track.score import BEYOND_PAPER_FIELDS, WEIGHT_FIELDS
from mocap.track.score import MOTION_CAP, MOTION_SIGMA_M, REGION_WEIGHT  # noqa: F401 (re-exported: the score's constants)
from mocap.track.smooth import SmootherConfig

#: Total budget below which the ``auto`` policy gives every evaluation to the region step.
AUTO_SPLIT_THRESHOLD = 200
#: Share of a budget of at least :data:`AUTO_SPLIT_THRESHOLD` that the ``auto`` policy gives the
#: region step of a registration with keypoints (without: half, the paper's). The region step
#: carries the keypoint distance too; from the last frame's pose it converges in about 500
#: evaluations, and the edge step after it stops within about 50-130, so half each left the region
#: step cut off at 250 on every frame (docs/research-log.md, 2026-11-30).
KEYPOINT_REGION_SHARE = 0.8
#: Where the edge step's simplex starts: the region step's final simplex (paper) or a fresh one.
EDGE_STARTS = ("region_simplex", "fresh")
#: Size of a fresh edge-step simplex (``edge_start="fresh"``, the paper's Fig. 8) relative to the
#: initial steps.
FRESH_STEP_SCALE = 3.0
#: Size of the recovery simplex (from the last good pose) relative to the initial steps.
RECOVERY_STEP_SCALE = 2.5
#: Skin regions smaller than this (pixels) are left out by hand re-acquisition.
MIN_SKIN_BLOB_PIXELS = 2
#: Hand re-acquisition reaches for at most this many unexplained skin regions a frame, the
#: largest: a body has two hands. On a real 128x96 clip the background left 7.6 such regions a
#: frame, whose reaches took a quarter of the frame (docs/research-log.md, issue 50).
MAX_REACH_TARGETS = 2
#: Kinematic jumps refined per frame: the lowest-F ones.
JUMPS_REFINED = 2
#: Share of the edge step's evaluations that the gradient step takes when it is on (one
#: gradient is one render, counted as one evaluation).
GRADIENT_SHARE = 0.1
#: Largest move per Gauss–Newton iteration of the gradient step, relative to the initial simplex steps.
GRADIENT_SCALE = 1.0
#: Pixels of edge distance per unit of F in the gradient step's score (eq. 2 + this x eq. 1): the
#: tracker's hypothesis score's ratio (50 per unit of F against 2 per pixel).
GRADIENT_REGION_WEIGHT = 25.0
#: Hypotheses whose joints are on average closer than this (metres) are merged, the better kept.
MERGE_DISTANCE_M = 0.02
#: Initial simplex step of the three root coordinates, metres (chosen with ``angle_step_deg`` on
#: the six synthetic sequences with three seeds; see docs/research-log.md).
POSITION_STEP_M = 0.05
#: A frame with F above this is a region failure (F is in [0, 1]).
REGION_FAILURE_THRESHOLD = 0.45
#: A frame with mean edge distance above this (pixels) is an edge failure.
EDGE_FAILURE_THRESHOLD_PX = 4.0
#: On a frame with 2D keypoints the failure flag reads the keypoint distance D_k (pixels): the
#: frame failed when D_k is above this, or when F and the edge distance are both above their
#: thresholds (a silhouette neither explains). Without keypoints F or the edge distance alone
#: flags it, as in the paper.
KEYPOINT_FAILURE_THRESHOLD_PX = 6.0
#: Pixels of mean edge distance per unit of F in the registration's steps with keypoints
#: (:meth:`TrackerConfig.keypoint_step_weights`); the score's own is ``TrackerConfig.edge_weight``.
EDGE_WEIGHT = 2.0


@dataclass(frozen=True)
class TrackerConfig(JsonConfig):
    """Settings of the tracker (saved in ``run.json``; JSON with unknown keys rejected).

    Attributes
    ----------
    evaluations : int
        Cost evaluations per frame of the leading hypothesis's two-step registration, both
        steps together (the paper's "iterations"); at least 1.
    split : str
        ``"auto"`` (paper's policy; with keypoints the region step takes
        :data:`KEYPOINT_REGION_SHARE` of budgets from :data:`AUTO_SPLIT_THRESHOLD`: see
        :func:`split_budget`) or ``"R:E"``, e.g. ``"250:250"`` (scaled to ``evaluations``).
    edge_start : str
        ``"region_simplex"`` (paper) or ``"fresh"`` (a new simplex of :data:`FRESH_STEP_SCALE`
        times the initial steps around the region step's best pose; the paper's Fig. 8).
    angle_step_deg : float, degrees
        Initial simplex step of the 20 angles (20 degrees and :data:`POSITION_STEP_M` were
        chosen on the six synthetic sequences with three seeds; see docs/research-log.md).
    ftol : float
        Convergence: relative spread of the simplex values (the paper's test).
    recovery : bool
        Beyond the paper: retry a failed frame from the last good pose with a wider simplex.
    mesh_resolution : int
        Mesh level of detail; 0 chooses it from the image size.
    hand_reacquisition : bool
        Beyond the paper: skin regions of the image that the model's hands and head leave
        unexplained are taken for a lost hand; either arm is posed to reach each (inverse
        kinematics) and the best such pose is registered (``hypothesis_evaluations``) as a
        further hypothesis.
    reacquisition_distance_px : float, pixels
        A skin region (of at least :data:`MIN_SKIN_BLOB_PIXELS`) whose centroid is farther than
        this from both projected hands triggers it.
    beam : int
        Hypotheses kept per frame (1: a single-hypothesis tracker, as the paper's).
    hypothesis_evaluations : int
        Evaluations of the two-step registration of every hypothesis but the leading one (and of
        a re-acquired hand's).
    jumps : bool
        Propose the kinematic jumps of the leading hypothesis (each arm's depth branches and the
        torso's front/back mirror, :mod:`mocap.body.jumps`); the :data:`JUMPS_REFINED`
        lowest-F ones are refined by a short registration of ``jump_evaluations``.
    jump_evaluations : int
        Evaluations of each jump's refinement.
    lag : int, frames
        Online decoding: a frame's pose is decided ``lag`` frames later, by the best path
        (Viterbi) through the hypotheses of the frames since. 0 takes the best hypothesis of
        each frame at once.
    offline : bool
        Decode the whole sequence at its end instead (the best path through every frame).
    keypoint_weight : float
        Beyond the paper, only when 2D keypoints are given: score per pixel of keypoint
        distance D_k (:class:`mocap.cost.KeypointCost`). The registration steps add D_k at the
        same rate relative to their own cost: the region step minimises
        ``F + keypoint_weight / REGION_WEIGHT * D_k``, the edge step
        ``D_c + keypoint_weight / EDGE_WEIGHT * D_k`` (:data:`REGION_WEIGHT`, :data:`EDGE_WEIGHT`). Without
        keypoints it changes nothing; 0: the keypoints are not a term (the lifter may still read them).
    lifter_weight : float
        With keypoints, switches the learned lifter on (> 0; 0: off): its hypotheses of the frame's
        keypoints join the proposal stage (:class:`mocap.track.proposals.LifterSource`), and the score
        adds ``lifter_weight`` per nat of its negative log-density at a candidate's joints (about the
        neck, :meth:`mocap.track.lifter.Lifter.log_density`), counted from the density at the
        lifter's most probable hypothesis and capped (:data:`mocap.track.proposals.LIFTER_ENERGY_CAP`);
        every candidate of a frame, tracked or proposed, pays it. 0.5 was the best of 0 / 0.2 / 0.5 / 1.5 on seed 0; on the unseen seed 23
        with oracle keypoints it took the tracker from 78 to 71 mm median and from 19.9 % to 16.5 %
        of frames over 100 mm (the lifter's proposals alone; docs/research-log.md, issue 29).
    labelling_weight : float
        With keypoints, score per nat of the labelling term
        (:func:`mocap.track.score.labelling_term`): a candidate that reads the keypoints with left
        and right swapped on a frame whose detector shows the person's front pays
        :data:`~mocap.track.score.FRONT_SWAP_NATS` (a body turned round with swapped labels
        projects as the right one does); 0: off.
    lifter_file : str or None
        The lifter's file (:meth:`mocap.track.lifter.Lifter.load`); None: the shipped one. An
        experiment's lifter trained without a subject is measured on that subject this way
        (``experiments.peers --only cmu``); read at the first frame that is lifted.
    prior_weight : float
        Score per nat of the pose prior's negative log-density (:mod:`mocap.body.prior`); 0: off.
    edge_weight : float
        Score per pixel of mean edge distance (the region's is :data:`REGION_WEIGHT` per unit of F,
        the unit of the score). The registration's steps keep their own balance (:data:`EDGE_WEIGHT`).
    motion_weight : float
        Multiplies the motion term between consecutive frames' hypotheses
        (:func:`mocap.track.score.transition_term`: the joints' truncated quadratic,
        :data:`MOTION_SIGMA_M`, :data:`MOTION_CAP`, plus the chest heading's,
        :data:`~mocap.track.score.TURN_SIGMA_DEG`, :data:`~mocap.track.score.TURN_CAP`); 0: the
        decoder takes each frame's best unary score. The score's weights (``edge_weight``,
        ``keypoint_weight``, ``prior_weight``, ``lifter_weight``, ``motion_weight``: the table
        :data:`mocap.track.score.TERMS`) score every frame, with keypoints or without. Weights of
        their own for frames without keypoints, fitted on data (``python -m experiments.fit_score``
        on candidates recorded without keypoints, seeds 0-1: edge 0.01516, prior 0.00708, motion 0),
        improved the unseen seeds 41 and 43 (141 / 125 -> 116 / 119 mm median) but failed the
        end-to-end check of a 16-frame clip at 300 evaluations (165 mm against a bound of 110), and
        with the motion term kept they lost on seed 43: not shipped, and the ``silhouette_*`` twins
        that held them removed (docs/research-log.md, issues 34 and 39).
    proposals_refined : int
        Proposals of each source refined per frame: the lowest-F ones (0: the stage is off).
    proposal_evaluations : int
        Evaluations of each proposal's refinement.
    proposal_gate : float or None
        Nats: a proposal is refined only when its unrefined unary score is at most this above the
        unrefined score, on the same frame, of the pose the beam's leader had (None: every
        ``proposals_refined`` lowest are refined). On seed 0 the lifter's refined proposals made 0.5 %
        (MediaPipe) and 1.1 % (true 2D) of the decided poses for a sixth of the budget, and all but
        one of those started at most 5 nats above the leader's pose, which most did not
        (docs/research-log.md, issue 50 item 6).
    mirrors : bool
        On frames with keypoints, the converged leader's depth alternatives
        (:func:`mocap.track.branches.depth_alternatives`: each arm's upper arm, forearm or both
        flipped in depth about their parent joint, same projections and bone lengths, within the
        joint limits) join the candidates, scored where they stand (or polished by
        ``mirror_evaluations``), and every frame's mirrors stay in the decoder's states beside the
        beam (not re-registered), so that a mirrored branch's path links to the previous frame's
        same mirror and the Viterbi over the lag sums its evidence before the branch switches.
    mirror_evaluations : int
        Evaluations of each mirror's polish (0: scored exactly where it stands).
    gradient_step : bool
        Beyond the paper (its future work): after the edge step, a bounded Gauss–Newton descent
        of eq. (2) on its analytic gradient (:func:`mocap.optimize.minimize_edge_gauss_newton`),
        with :data:`GRADIENT_SHARE` of the edge step's evaluations.
    smoothing : SmootherConfig
        The written poses' fixed-lag smoother over the decoding's ``lag`` (the whole clip
        offline): :mod:`mocap.track.smooth`; off in :meth:`paper`.
    """

    evaluations: int = 500
    split: str = "auto"
    edge_start: str = "region_simplex"
    angle_step_deg: float = 20.0
    ftol: float = 1e-3
    recovery: bool = True
    mesh_resolution: int = 0
    hand_reacquisition: bool = True
    reacquisition_distance_px: float = 6.0
    beam: int = 3
    hypothesis_evaluations: int = 150
    jumps: bool = True
    jump_evaluations: int = 80
    lag: int = 8
    offline: bool = False
    keypoint_weight: float = 2.0
    lifter_weight: float = 0.5
    lifter_file: str | None = None
    labelling_weight: float = 1.0
    prior_weight: float = 0.05
    edge_weight: float = 2.0
    motion_weight: float = 1.0
    proposals_refined: int = 2
    proposal_evaluations: int = 100
    proposal_gate: float | None = 5.0
    mirrors: bool = True
    mirror_evaluations: int = 0
    gradient_step: bool = False
    smoothing: SmootherConfig = SmootherConfig()

    def __post_init__(self) -> None:
        for name in ("beam",):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name} must be an integer of at least 1, got {v!r}")
        for name in ("evaluations", "hypothesis_evaluations", "jump_evaluations", "lag", "mesh_resolution",
                     "proposals_refined", "proposal_evaluations", "mirror_evaluations"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise ValueError(f"{name} must be a non-negative integer, got {v!r}")
        for name in ("recovery", "hand_reacquisition", "jumps", "offline", "gradient_step", "mirrors"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} must be true or false, got {getattr(self, name)!r}")
        if isinstance(self.smoothing, dict):         # TrackerConfig(**config.to_dict()) gives its dict
            object.__setattr__(self, "smoothing", SmootherConfig.from_dict(self.smoothing))
        if not isinstance(self.smoothing, SmootherConfig):
            raise ValueError(f"smoothing must be a SmootherConfig, got {self.smoothing!r}")
        if self.lifter_file is not None and (not isinstance(self.lifter_file, str) or not self.lifter_file):
            raise ValueError(f"lifter_file must be a file name or None, got {self.lifter_file!r}")
        split_budget(self.evaluations, self.split)          # validates the split
        if self.edge_start not in EDGE_STARTS:
            raise ValueError(f"edge_start must be one of {EDGE_STARTS}, got {self.edge_start!r}")
        for name in ("angle_step_deg", "reacquisition_distance_px"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise ValueError(f"{name} must be a finite positive number, got {v!r}")
        gate = self.proposal_gate
        if gate is not None and (isinstance(gate, bool) or not isinstance(gate, (int, float)) or not math.isfinite(gate)):
            raise ValueError(f"proposal_gate must be a finite number of nats or None, got {gate!r}")
        for name in ("ftol",) + WEIGHT_FIELDS:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise ValueError(f"{name} must be finite and non-negative, got {v!r}")

    @classmethod
    def paper(cls, **changes) -> "TrackerConfig":
        """The paper's method: one hypothesis, no recovery, re-acquisition, jumps, proposals, prior
        or keypoints (the weights of the score's terms beyond the paper,
        :data:`~mocap.track.score.BEYOND_PAPER_FIELDS`, at 0).

        Parameters
        ----------
        **changes
            Fields to set as well (the budget, split and edge start the experiments sweep);
            unknown names raise TypeError.
        """
        return replace(cls(recovery=False, hand_reacquisition=False, beam=1, jumps=False, lag=0, gradient_step=False,
                           smoothing=SmootherConfig(on=False), mirrors=False,
                           **{name: 0.0 for name in BEYOND_PAPER_FIELDS}),
                       **changes)

    @property
    def uses_lifter(self) -> bool:
        """Whether frames with keypoints are lifted (``lifter_weight`` > 0): the lifter's hypotheses
        are then the proposal stage's keypoint source and its density a term of the score."""
        return self.lifter_weight > 0

    def keypoint_step_weights(self) -> tuple[float, float]:
        """Weight of the keypoint distance in the region step (units of F per pixel) and in the
        edge step (pixels per pixel): ``keypoint_weight`` over :data:`REGION_WEIGHT` and :data:`EDGE_WEIGHT`."""
        if self.keypoint_weight == 0:
            return 0.0, 0.0
        return self.keypoint_weight / REGION_WEIGHT, self.keypoint_weight / EDGE_WEIGHT

    def steps(self) -> np.ndarray:
        """Initial simplex steps, shape (23,): metres for the root, radians for the angles."""
        return np.r_[np.full(3, POSITION_STEP_M), np.full(N_PARAMETERS - 3, math.radians(self.angle_step_deg))]


#: Fewest evaluations the gradient step runs with: its start and one step, each rendering the
#: edge distance and F.
MIN_GRADIENT_EVALUATIONS = 4


def gradient_budget(edge_evaluations: int) -> int:
    """Evaluations the gradient step takes out of the edge step's ``edge_evaluations`` when it is
    on: :data:`GRADIENT_SHARE` of them, or 0 (the edge step keeps them all) when that is fewer
    than :data:`MIN_GRADIENT_EVALUATIONS`."""
    n = int(round(GRADIENT_SHARE * max(edge_evaluations, 0)))
    return n if n >= MIN_GRADIENT_EVALUATIONS else 0


def split_budget(total: int, split: str, keypoints: bool = False) -> tuple[int, int]:
    """Split a per-frame evaluation budget between the region and the edge step.

    Parameters
    ----------
    total : int
        Evaluations per frame.
    split : str
        ``"auto"``: all to the region step below :data:`AUTO_SPLIT_THRESHOLD`, else half each
        (the paper's policy, section 5), or :data:`KEYPOINT_REGION_SHARE` to the region step with
        ``keypoints``. ``"R:E"``: in that proportion (``"1:0"`` all region, ``"0:1"`` all edge);
        ``R + E`` need not equal ``total``.
    keypoints : bool
        The registration adds a keypoint distance to both steps (the paper had none).

    Returns
    -------
    (int, int)
        Region and edge evaluations, adding up to ``total``.
    """
    if split == "auto":
        if total < AUTO_SPLIT_THRESHOLD:
            return total, 0
        if keypoints:
            region = int(round(total * KEYPOINT_REGION_SHARE))
            return region, total - region
        return total - total // 2, total // 2
    parts = split.split(":") if isinstance(split, str) else []
    try:
        r, e = (float(p) for p in parts)
    except ValueError:
        raise ValueError(f"split must be 'auto' or 'R:E' with two non-negative numbers, got {split!r}") from None
    if not (math.isfinite(r) and math.isfinite(e)) or r < 0 or e < 0 or r + e == 0:
        raise ValueError(f"split must be 'auto' or 'R:E' with two non-negative numbers not both 0, got {split!r}")
    region = int(round(total * r / (r + e)))
    return region, total - region
