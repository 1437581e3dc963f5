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

#: Total budget below which the ``auto`` policy gives every evaluation to the region step.
AUTO_SPLIT_THRESHOLD = 200
#: Where the edge step's simplex starts: the region step's final simplex (paper) or a fresh one.
EDGE_STARTS = ("region_simplex", "fresh")
#: Size of a fresh edge-step simplex (``edge_start="fresh"``, the paper's Fig. 8) relative to the
#: initial steps.
FRESH_STEP_SCALE = 3.0
#: Size of the recovery simplex (from the last good pose) relative to the initial steps.
RECOVERY_STEP_SCALE = 2.5
#: Skin regions smaller than this (pixels) are left out by hand re-acquisition.
MIN_SKIN_BLOB_PIXELS = 2
#: Kinematic jumps refined per frame: the lowest-F ones.
JUMPS_REFINED = 2
#: Hypotheses whose joints are on average closer than this (metres) are merged, the better kept.
MERGE_DISTANCE_M = 0.02


@dataclass(frozen=True)
class TrackerConfig(JsonConfig):
    """Settings of the tracker (saved in ``run.json``; JSON with unknown keys rejected).

    Attributes
    ----------
    evaluations : int
        Cost evaluations per frame of the leading hypothesis's two-step registration, both
        steps together (the paper's "iterations"); at least 1.
    split : str
        ``"auto"`` (paper's policy) or ``"R:E"``, e.g. ``"250:250"`` (scaled to ``evaluations``).
    edge_start : str
        ``"region_simplex"`` (paper) or ``"fresh"`` (a new simplex of :data:`FRESH_STEP_SCALE`
        times the initial steps around the region step's best pose; the paper's Fig. 8).
    position_step_m : float, metres
        Initial simplex step of the three root coordinates.
    angle_step_deg : float, degrees
        Initial simplex step of the 20 angles (20 degrees and 5 cm were chosen on the six
        synthetic sequences with three seeds; see docs/research-log.md).
    ftol : float
        Convergence: relative spread of the simplex values (the paper's test).
    region_failure_threshold : float
        A frame with F above this is a region failure (F is in [0, 1]).
    edge_failure_threshold_px : float, pixels
        A frame with mean edge distance above this is an edge failure.
    keypoint_failure_threshold_px : float, pixels
        On a frame with 2D keypoints the failure flag reads the keypoint distance D_k: the frame
        failed when D_k is above this, or when F and the edge distance are both above their
        thresholds (a silhouette neither explains). Without keypoints F or the edge distance
        alone flags it, as in the paper.
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
    region_weight, edge_weight : float
        Score of a hypothesis per unit of F and per pixel of mean edge distance.
    keypoint_weight : float
        Beyond the paper, only when 2D keypoints are given: score per pixel of keypoint
        distance D_k (:class:`mocap.cost.KeypointCost`). The registration steps add D_k at the
        same rate relative to their own cost: the region step minimises
        ``F + keypoint_weight / region_weight * D_k``, the edge step
        ``D_c + keypoint_weight / edge_weight * D_k``; and a keypoint source joins the proposal
        stage (the learned lifter's hypotheses, :class:`mocap.track.proposals.LifterSource`). Without
        keypoints it changes nothing.
    lifter_weight : float
        With keypoints: score per nat of the learned lifter's negative log-density at a candidate's
        joints (about the neck, :meth:`mocap.track.lifter.Lifter.log_density`), counted from the
        density at the lifter's most probable hypothesis and capped
        (:data:`mocap.track.tracker.LIFTER_ENERGY_CAP`); every candidate of a frame, tracked or
        proposed, pays it. 0.5 was the best of 0 / 0.2 / 0.5 / 1.5 on seed 0; on the unseen seed 23
        with oracle keypoints it took the tracker from 78 to 71 mm median and from 19.9 % to 16.5 %
        of frames over 100 mm (the lifter's proposals alone; docs/research-log.md, issue 29).
    prior_weight : float
        Score per nat of the pose prior's negative log-density (:mod:`mocap.body.prior`); 0: off.
    motion_sigma_m : float, metres
        Motion term between hypotheses of consecutive frames: half the mean squared joint
        displacement over ``motion_sigma_m**2``...
    motion_cap : float
        ...at most this much (a truncated quadratic): a jump between branches or to a
        re-acquired arm costs a fixed price that a clearly better fit pays.
    proposals_refined : int
        Proposals of each source refined per frame: the lowest-F ones (0: the stage is off).
    proposal_evaluations : int
        Evaluations of each proposal's refinement.
    """

    evaluations: int = 500
    split: str = "auto"
    edge_start: str = "region_simplex"
    position_step_m: float = 0.05
    angle_step_deg: float = 20.0
    ftol: float = 1e-3
    region_failure_threshold: float = 0.45
    edge_failure_threshold_px: float = 4.0
    keypoint_failure_threshold_px: float = 6.0
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
    region_weight: float = 50.0
    edge_weight: float = 2.0
    keypoint_weight: float = 2.0
    lifter_weight: float = 0.5
    prior_weight: float = 0.05
    motion_sigma_m: float = 0.05
    motion_cap: float = 8.0
    proposals_refined: int = 2
    proposal_evaluations: int = 100

    def __post_init__(self) -> None:
        for name in ("beam",):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name} must be an integer of at least 1, got {v!r}")
        for name in ("evaluations", "hypothesis_evaluations", "jump_evaluations", "lag", "mesh_resolution",
                     "proposals_refined", "proposal_evaluations"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise ValueError(f"{name} must be a non-negative integer, got {v!r}")
        for name in ("recovery", "hand_reacquisition", "jumps", "offline"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} must be true or false, got {getattr(self, name)!r}")
        split_budget(self.evaluations, self.split)          # validates the split
        if self.edge_start not in EDGE_STARTS:
            raise ValueError(f"edge_start must be one of {EDGE_STARTS}, got {self.edge_start!r}")
        for name in ("position_step_m", "angle_step_deg",
                     "edge_failure_threshold_px", "keypoint_failure_threshold_px", "region_failure_threshold",
                     "reacquisition_distance_px",
                     "motion_sigma_m", "motion_cap"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise ValueError(f"{name} must be a finite positive number, got {v!r}")
        for name in ("ftol", "region_weight", "edge_weight", "keypoint_weight", "lifter_weight", "prior_weight"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise ValueError(f"{name} must be finite and non-negative, got {v!r}")
        if self.keypoint_weight > 0 and (self.region_weight == 0 or self.edge_weight == 0):
            raise ValueError("keypoint_weight > 0 needs positive region_weight and edge_weight (the registration "
                             "steps weigh the keypoint distance relative to them)")

    @classmethod
    def paper(cls, **changes) -> "TrackerConfig":
        """The paper's method: one hypothesis, no recovery, re-acquisition, jumps, proposals, prior
        or keypoints.

        Parameters
        ----------
        **changes
            Fields to set as well (the budget, split and edge start the experiments sweep);
            unknown names raise TypeError.
        """
        return replace(cls(recovery=False, hand_reacquisition=False, beam=1, jumps=False, lag=0,
                           prior_weight=0.0, keypoint_weight=0.0, lifter_weight=0.0),
                       **changes)

    @property
    def uses_lifter(self) -> bool:
        """Whether frames with keypoints are lifted (``keypoint_weight`` > 0: the lifter's hypotheses
        are then the proposal stage's keypoint source, and its score term counts when
        ``lifter_weight`` > 0)."""
        return self.keypoint_weight > 0

    def keypoint_step_weights(self) -> tuple[float, float]:
        """Weight of the keypoint distance in the region step (units of F per pixel) and in the
        edge step (pixels per pixel): ``keypoint_weight`` over ``region_weight`` and ``edge_weight``."""
        if self.keypoint_weight == 0:
            return 0.0, 0.0
        return self.keypoint_weight / self.region_weight, self.keypoint_weight / self.edge_weight

    def steps(self) -> np.ndarray:
        """Initial simplex steps, shape (23,): metres for the root, radians for the angles."""
        return np.r_[np.full(3, self.position_step_m), np.full(N_PARAMETERS - 3, math.radians(self.angle_step_deg))]


def split_budget(total: int, split: str) -> tuple[int, int]:
    """Split a per-frame evaluation budget between the region and the edge step.

    Parameters
    ----------
    total : int
        Evaluations per frame.
    split : str
        ``"auto"``: all to the region step below :data:`AUTO_SPLIT_THRESHOLD`, else half each
        (the paper's policy, section 5). ``"R:E"``: in that proportion (``"1:0"`` all region,
        ``"0:1"`` all edge); ``R + E`` need not equal ``total``.

    Returns
    -------
    (int, int)
        Region and edge evaluations, adding up to ``total``.
    """
    if split == "auto":
        if total < AUTO_SPLIT_THRESHOLD:
            return total, 0
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
