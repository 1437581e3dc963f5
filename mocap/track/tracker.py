"""The tracker: a beam of pose hypotheses per frame, decoded over time.

Every frame, each hypothesis kept from the previous frame is extended by the two-step
registration (:func:`~mocap.track.registration.register`; the leading one with the full
budget, the others with ``hypothesis_evaluations``). Proposals compete with them: a recovery
from the last good pose when the leader fails, hand re-acquisition when a skin region is left
unexplained, the leader's kinematic jumps (:mod:`mocap.body.jumps`), on frames with keypoints the
converged leader's exact depth alternatives (:mod:`mocap.track.branches`, origin ``mirror``: the
same projections, scored where they stand), and the proposal stage's
poses read from the current image (:class:`~mocap.track.proposals.ProposalSource`: from 2D
keypoints, the learned lifter's whole-body hypotheses), each refined by a short registration. Every
candidate gets a **unary score** (``REGION_WEIGHT * F + edge_weight * edge distance +
prior_weight * pose-prior energy``; on frames with 2D keypoints plus ``keypoint_weight *
keypoint distance``, which every registration of the frame then also adds, and ``lifter_weight``
times the lifter's negative log-density at the candidate's joints); between consecutive frames a **motion term**
(``motion_weight`` times half the mean squared joint displacement over ``MOTION_SIGMA_M**2``, capped) links
them. The terms, their weights and the motion term are :mod:`mocap.track.score`'s table. Each frame's
candidates and their terms before the weights stay readable in :attr:`Tracker.scored`
(:class:`ScoredCandidate`; ``experiments.fit_score`` fits the weights on them). The forward
Viterbi recursion (:func:`~mocap.track.decode.viterbi_step`) gives each candidate the cost of
the best path to it, and its predecessor on that path: its *parent*. Every candidate's chest heading
(kept unwrapped, limits ±720°) is then brought to the 2π-equivalent nearest its parent's
(:func:`mocap.body.pose.heading_near`), whatever brought it (a lifter's proposal, a jump, a
re-acquisition: any of them may bring a heading wrapped to ±180°); the score and the motion term
see joints only, so this changes no cost, and the decoded path never turns a whole turn from one
frame to the next (issue 44). Near-duplicates are merged and the ``beam`` cheapest survive, and beside them
the frame's mirrors: decoder states that the next frame does not register, so that a mirrored
branch's path runs through the previous frame's same mirror (a small motion term) and a switch of
branch is decided by the evidence summed over the lag rather than by one frame's margin.

A frame's pose is decided ``lag`` frames later by backtracking the best path from the newest
frame (online), or at the end of the sequence through all frames (``offline``). With
``beam=1``, ``lag=0`` and every proposal off this is the paper's single-hypothesis tracker.
The pose written is then smoothed (``config.smoothing``, :mod:`mocap.track.smooth`): the
fixed-lag smoother reads the best path's tentative poses of the frames not yet decided, and
the frame's residuals (region, edge, keypoint distance, the failure flag) are those of the
smoothed pose, evaluated on the frame's image then (the window keeps each frame's label image,
distance map and keypoints for that).

A frame's registrations and proposal scoring run on ``threads`` threads (:class:`Tracker`): the
compiled costs hold no interpreter lock, each task has cost objects of its own, and the tracker
reads the results in the order it asked for them, so the decisions are the same, bit for bit,
for every thread count.

The tracker streams: :meth:`Tracker.push` takes a prepared frame and returns the frames whose
pose is now final, :meth:`Tracker.finish` the rest; :meth:`Tracker.state` and
:meth:`Tracker.restore` carry its exact state across a resumed run. Online, its memory holds
``lag + 1`` frames of hypotheses whatever the length of the video.
"""
from __future__ import annotations

import functools
import json
import math
import queue
import time
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from mocap.body.ik import ARM_JOINTS, place_arm, reach_arm
from mocap.body.model import BodyModel
from mocap.body.pose import HEADING, PARAMETER_INDEX, check_pose, clamp_to_limits, heading_near
from mocap.body.prior import PosePrior, default_prior
from mocap.body.skeleton import JOINT_INDEX
from mocap.cost import EdgeCost, KeypointCost, RegionCost
from mocap.imaging.edges import distance_map
from mocap.imaging.prepare import PreparedFrame
from mocap.io.keypoints import SWAPPED_JOINTS, Keypoints
from mocap.labels import BACKGROUND
from mocap.render.camera import Camera
from mocap.render.rasterize import render
from mocap.track.branches import depth_alternatives
from mocap.track.config import JUMPS_REFINED, MERGE_DISTANCE_M, RECOVERY_STEP_SCALE, TrackerConfig, split_budget
from mocap.track.decode import backtrack, viterbi_step
from mocap.track.lifter import LiftedHypotheses, Lifter
from mocap.track.proposals import (LifterSource, ProposalContext, ProposalSource, arm_reach_proposals, jump_proposals,
                                   reach_jobs, unexplained_hands)
from mocap.track.registration import Registration, failed_residuals, register
from mocap.track.score import (MOTION, UNARY_TERMS, ScoredCandidate, front_price, labelling_term, transition_term,
                               weighted_sum, weights)
from mocap.track.smooth import Smoother

#: Arm angles (degrees) of :meth:`Tracker.warm_up`'s pose: both forearms raised in front, where
#: each arm's depth mirrors are inside the limits.
WARM_UP_ARMS_DEG = {"r_shoulder_flex": 30.0, "r_shoulder_abd": 20.0, "r_elbow_flex": 90.0,
                    "l_shoulder_flex": 30.0, "l_shoulder_abd": 20.0, "l_elbow_flex": 90.0}
#: Index of the chest's heading in the pose vector.
_HEADING = PARAMETER_INDEX[HEADING]
#: Rows of the shoulders in the joints (:data:`~mocap.body.skeleton.JOINT_NAMES`).
_R_SHOULDER, _L_SHOULDER = JOINT_INDEX["r_shoulder"], JOINT_INDEX["l_shoulder"]


@dataclass(kw_only=True)
class FrameResult:
    """What the tracker decided for one frame (one row of ``poses.csv``).

    ``timings_ms`` has ``prepare``, ``region`` and ``edge`` (the leading hypothesis's two
    steps), ``beam`` (everything after them: the other hypotheses, recovery, re-acquisition,
    jumps, the proposal stage and the decoder's step), ``proposals`` (the proposal stage alone,
    part of ``beam``) and ``total`` (milliseconds; plus the image side's parts ``prepare_*``).
    ``hypothesis`` is the chosen hypothesis's rank in its frame's beam when that frame was
    tracked (0: it led), ``score`` its unary score and ``origin`` what produced it in that
    frame (``tracked``, ``recovery``, ``reacquisition``, ``jump``, a proposal source's ``origin``,
    ``empty`` or ``initial``). ``pose`` and ``joints`` are the smoothed ones when
    ``config.smoothing`` is on, and ``region_residual``, ``edge_residual``,
    ``keypoint_residual`` (NaN without keypoints) and ``failed`` are theirs; ``score`` and
    ``edge_residual_after_region`` stay the decoded hypothesis's, and ``smoothed_mm`` is the
    mean joint distance from the decoded pose (``decoded_pose``) to the written one
    (millimetres; 0 unsmoothed). ``labels_swapped``: the chosen hypothesis read the frame's
    keypoints with left and right swapped (the detector named the person's left arm the right
    one; False without keypoints).
    """

    frame: int
    pose: np.ndarray
    joints: np.ndarray
    region_residual: float
    edge_residual: float
    edge_residual_after_region: float
    failed: bool
    empty: bool
    origin: str
    evaluations: int
    region_iterations: int
    edge_iterations: int
    timings_ms: dict[str, float] = field(default_factory=dict)
    hypothesis: int = 0
    score: float = math.nan
    keypoint_residual: float = math.nan
    smoothed_mm: float = 0.0
    decoded_pose: np.ndarray | None = None
    labels_swapped: bool = False


@dataclass
class _Hypothesis:
    pose: np.ndarray
    joints: np.ndarray
    region_residual: float
    edge_residual: float
    edge_residual_after_region: float
    failed: bool
    origin: str
    unary: float
    region_iterations: int
    edge_iterations: int
    swapped: bool = False               # it reads the frame's keypoints with left and right swapped


@dataclass
class _Evidence:
    """What a frame's residuals are evaluated on when its pose is written (smoothing on)."""

    labels: np.ndarray                  # (H, W) uint8: PreparedFrame.labels
    distance: np.ndarray                # (H, W) float32: PreparedFrame.distance
    keypoints: np.ndarray | None        # (10, 3): u, v (working pixels, NaN absent), confidence


@dataclass
class _Frame:
    index: int
    empty: bool
    hypotheses: list[_Hypothesis]
    cost: np.ndarray            # best-path cost of each hypothesis (lowest first)
    back: np.ndarray            # its predecessor among the previous frame's hypotheses
    evaluations: int
    timings: dict[str, float]
    evidence: _Evidence | None = None   # smoothing on: the frame's images and keypoints (None when empty)


class Tracker:
    """Tracks one actor frame after frame (see the module).

    Parameters
    ----------
    model : BodyModel
        The calibrated actor. Its mesh is used as is when ``config.mesh_resolution`` is 0, and
        rebuilt at that level of detail otherwise.
    camera : Camera
    config : TrackerConfig
    initial_pose : array_like, shape (23,)
        Pose in the first frame (from calibration), metres and radians.
    prior : PosePrior, optional
        Pose prior of the score (default: the shipped one, when ``config.prior_weight > 0``).
    sources : sequence of ProposalSource, optional
        The proposal stage's sources (default: :func:`proposal_sources` of ``config``);
        experiments add others (an oracle) this way.
    lifter : Lifter, optional
        The 2D->3D lifter of frames with keypoints when ``config.uses_lifter`` (``lifter_weight``
        > 0); default: ``config.lifter_file`` (None: the shipped one), loaded at the first frame
        with keypoints. The tracker's :class:`LifterSource` (:attr:`lifting`) owns it: lifts each
        such frame once, for the proposal stage and the score.
    threads : int
        Threads a frame's registrations and proposal scoring run on (the compiled costs hold
        no interpreter lock): the leader beside the other hypotheses and the proposal stage,
        then the recovery, re-acquisition, jumps and mirrors beside each other. The decisions
        are the same, bit for bit, for every count; 1 (default) runs everything on the calling
        thread. :meth:`begin` starts the next frame's leader while the caller writes the last
        frame's results. :meth:`close` stops the threads.
    """

    def __init__(self, model: BodyModel, camera: Camera, config: TrackerConfig, initial_pose,
                 prior: PosePrior | None = None, sources: Sequence[ProposalSource] | None = None,
                 lifter: Lifter | None = None, threads: int = 1) -> None:
        if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or threads < 1:
            raise ValueError(f"threads must be a positive integer, got {threads!r}")
        if config.mesh_resolution and model.mesh.resolution != config.mesh_resolution:
            model = model.with_resolution(config.mesh_resolution)
        self.model, self.camera, self.config = model, camera, config
        self.prior = prior if prior is not None else (default_prior() if config.prior_weight > 0 else None)
        #: The score's weights (:func:`mocap.track.score.weights`, every frame's).
        self.weights: np.ndarray = weights(config)
        #: The lifting (None when ``config`` does not use the lifter); also the default keypoint source.
        self.lifting: LifterSource | None = LifterSource(lifter, config.lifter_file) if config.uses_lifter else None
        self.sources: tuple[ProposalSource, ...] = tuple(proposal_sources(config, self.lifting) if sources is None
                                                         else sources)
        self.candidates: list[tuple[str, np.ndarray]] = []
        #: The last frame's candidates with their score's terms (empty after an empty frame).
        self.scored: list[ScoredCandidate] = []
        #: The last frame's lifted hypotheses (None when it was not lifted).
        self.lifted: LiftedHypotheses | None = None
        q = clamp_to_limits(check_pose(initial_pose, name="initial pose"))
        start = _Hypothesis(q, model.joint_positions(q), math.nan, math.nan, math.nan, False, "initial",
                            0.0, 0, 0)
        self._beam: list[_Hypothesis] = [start]
        self._cost = np.zeros(1)
        self._window: deque[_Frame] = deque()
        self.last_good = q
        #: The written poses' smoother (None when ``config.smoothing`` is off).
        self.smoother: Smoother | None = Smoother(config.smoothing) if config.smoothing.on else None
        #: Threads a frame's registrations run on (the decisions are the same for every count).
        self.threads = int(threads)
        self._pool = ThreadPoolExecutor(self.threads, thread_name_prefix="mocap-tracker") if self.threads > 1 else None
        self._begun: _Begun | None = None

    def warm_up(self, keypoints: bool = True) -> None:
        """Load every compiled kernel this tracker's frames call (on a cold cache: compile them,
        seconds each) before its first frame, leaving this tracker as it was.

        A tracker of the same model, camera, configuration, prior and sources tracks a frame of
        the model rendered in :data:`WARM_UP_ARMS_DEG` at this tracker's pose (both arms' depth
        mirrors inside the limits) without keypoints and, with ``keypoints``, a second one with
        its joints projected as keypoints (the mirrors, the keypoint distance and the lifter,
        loaded now when the configuration uses it); then the arm solvers of the stages that run
        only on some frames are called once for each arm (hand re-acquisition's
        :func:`~mocap.body.ik.reach_arm`; with ``keypoints`` the mirrors'
        :func:`~mocap.body.ik.place_arm`, on targets beyond the arm's reach so that its polish runs). Each kernel gets
        the types of a real frame's (the costs convert their images), so no later frame
        compiles or loads one (``tests/track/test_tracker.py``).

        Parameters
        ----------
        keypoints : bool
            Whether frames may come with 2D keypoints (a run with a keypoint source).
        """
        pose = self._beam[0].pose.copy()
        for name, degrees in WARM_UP_ARMS_DEG.items():
            pose[PARAMETER_INDEX[name]] = math.radians(degrees)
        pose = clamp_to_limits(pose)
        lifter = self.lifting.lifter if self.lifting is not None and keypoints else None
        shadow = Tracker(self.model, self.camera, self.config, pose, prior=self.prior, sources=self.sources,
                         lifter=lifter)
        rendered = render(pose, self.model, self.camera)
        frame = PreparedFrame(rendered.labels, rendered.labels != BACKGROUND, rendered.edges,
                              distance_map(rendered.edges), False, {})
        joints = self.model.joint_positions(pose)
        shadow.push(0, frame)
        if keypoints:
            shadow.push(1, frame, Keypoints(self.camera.project(joints), np.ones(len(joints))))
        shadow.finish()
        for side in ("r", "l"):
            arm = [JOINT_INDEX[f"{side}_{j}"] for j in ARM_JOINTS]
            reach_arm(pose, self.model.skeleton, side, joints[arm[-1]])
            if keypoints:
                # targets 10 % farther from the shoulder than the arm reaches: the closed form
                # misses them, so the polish (a kernel of its own) runs too
                shoulder = joints[JOINT_INDEX[f"{side}_shoulder"]]
                place_arm(pose, self.model.skeleton, side, shoulder + 1.1 * (joints[arm] - shoulder))

    # -- streaming ---------------------------------------------------------------------------
    def push(self, frame_index: int, prepared, keypoints=None) -> list[FrameResult]:
        """Take one prepared frame (:class:`mocap.imaging.PreparedFrame`) and, where a detector
        gave them, its 2D keypoints (for the proposal sources that read them); return the frames
        whose pose is now final, oldest first.

        Online with ``lag`` L, the first L calls return nothing and each later call one frame;
        offline, nothing comes out before :meth:`finish`. Every frame pushed comes out once,
        in order.
        """
        frame = self._track(int(frame_index), prepared, keypoints)
        if self.smoother is not None and not frame.empty:
            frame.evidence = _Evidence(prepared.labels, prepared.distance, None if keypoints is None else
                                       np.column_stack([keypoints.uv, keypoints.confidence]))
        self._window.append(frame)
        self._beam, self._cost = frame.hypotheses, frame.cost
        leader = frame.hypotheses[0]
        if not frame.empty and not leader.failed:
            self.last_good = leader.pose
        if self.config.offline:
            return []
        out = []
        while len(self._window) > self.config.lag:
            out += self._decide(1)
        return out

    def begin(self, frame_index: int, prepared, keypoints=None) -> None:
        """Start the next frame's leader registration on the tracker's threads, so that it runs
        while the caller writes what :meth:`push` returned: ``push`` of the same frame (the
        same ``prepared`` and ``keypoints`` objects) then takes it up. The decisions are the
        same, bit for bit, with and without it; a ``push`` of anything else drops it. Nothing
        happens with one thread (``threads=1``), on an empty frame, or on one that cannot be
        tracked (its ``push`` raises the error)."""
        self._begun = None
        if self._pool is None or prepared.is_empty:
            return
        try:
            work = self._frame_work(prepared, keypoints)
        except ValueError:      # a frame that cannot be tracked: its push says why, not this
            return
        started = time.perf_counter()
        leading = work.submit(_timed_fit, self._beam[0].pose, self.config, self.config.evaluations)
        self._begun = _Begun(int(frame_index), prepared, keypoints, work, leading, started)

    def finish(self) -> list[FrameResult]:
        """The frames still undecided at the end of the video, decided by the best path (one
        smoother pass: the same poses as deciding them one by one)."""
        return self._decide(len(self._window)) if self._window else []

    def _decide(self, count: int) -> list[FrameResult]:
        """The ``count`` oldest frames of the window decided by the best path, smoothed, written."""
        frames = list(self._window)
        path = backtrack([f.back for f in frames[1:]], int(np.argmin(frames[-1].cost)))
        chosen = [f.hypotheses[k] for f, k in zip(frames, path)]
        if self.smoother is None:
            return [_result(self._window.popleft(), int(path[i])) for i in range(count)]
        weights = np.array([self.smoother.weights(None if f.evidence is None or f.evidence.keypoints is None
                                                  else _read_as(f.evidence.keypoints, h.swapped)[:, 2])
                            for f, h in zip(frames, chosen)])
        poses = self.smoother.smooth(np.array([h.pose for h in chosen]), np.array([h.joints for h in chosen]),
                                     weights, count, empty=[f.empty for f in frames])
        return [self._written(self._window.popleft(), int(path[i]), poses[i]) for i in range(count)]

    def _written(self, frame: _Frame, k: int, pose: np.ndarray) -> FrameResult:
        """Frame ``frame``'s result with the smoothed ``pose`` and the residuals there."""
        result = _result(frame, k)
        joints = self.model.joint_positions(pose)
        result.pose, result.joints = pose, joints
        result.smoothed_mm = 1e3 * float(np.linalg.norm(joints - frame.hypotheses[k].joints, axis=1).mean())
        evidence = frame.evidence
        if evidence is None:            # an empty frame: nothing to evaluate
            return result
        region = RegionCost(evidence.labels, self.model, self.camera)(pose)
        edge = EdgeCost(evidence.distance, self.model, self.camera)(pose)
        keypoint_cost = None
        if evidence.keypoints is not None and self.config.keypoint_weight != 0:
            kp = _read_as(evidence.keypoints, frame.hypotheses[k].swapped)
            keypoint_cost = KeypointCost(kp[:, :2], kp[:, 2], self.model, self.camera,
                                         foreground=evidence.labels != BACKGROUND)
        keypoint = math.nan if keypoint_cost is None or keypoint_cost.empty else keypoint_cost(pose)
        result.region_residual, result.edge_residual, result.keypoint_residual = region, edge, keypoint
        result.failed = failed_residuals(region, edge, keypoint,
                                         edge_checked=split_budget(self.config.evaluations, self.config.split)[1] > 0)
        return result

    @property
    def pending(self) -> int:
        """Frames pushed but not yet decided (at most ``lag`` online; all of them offline)."""
        return len(self._window)

    @property
    def hypotheses(self) -> list[np.ndarray]:
        """Poses of the current beam, best path cost first (metres, radians); after a frame with
        mirrors, its mirrors past the ``beam`` registered ones."""
        return [h.pose.copy() for h in self._beam]

    # -- one frame ---------------------------------------------------------------------------
    def costs(self, prepared) -> tuple[RegionCost, EdgeCost]:
        """Region and edge costs of one prepared frame, for this tracker's model, camera and config."""
        return (RegionCost(prepared.labels, self.model, self.camera),
                EdgeCost(prepared.distance, self.model, self.camera))

    def keypoint_cost(self, keypoints, labels: np.ndarray | None = None) -> KeypointCost | None:
        """The keypoint distance of a frame's :class:`~mocap.io.keypoints.Keypoints` (working
        camera pixels) for this tracker, under both labellings (``swap``: the lower of the
        detector's and the left/right swapped one), each keypoint gated by the person's region
        of the frame's label image ``labels`` (its pixels other than background; None: no gate);
        None when there are none or ``keypoint_weight`` is 0."""
        if keypoints is None or self.config.keypoint_weight == 0:
            return None
        cost = KeypointCost(keypoints.uv, keypoints.confidence, self.model, self.camera, swap=True,
                            foreground=None if labels is None else labels != BACKGROUND)
        return None if cost.empty else cost

    def _track(self, index: int, prepared, keypoints=None) -> _Frame:
        cfg = self.config
        t0 = time.perf_counter()
        begun, self._begun = self._begun, None
        timings = {f"prepare_{k}": 1e3 * v for k, v in prepared.timings.items()}
        timings["prepare"] = sum(timings.values())
        if prepared.is_empty:
            kept = [_Hypothesis(h.pose, h.joints, math.nan, math.nan, math.nan, False, "empty",
                                0.0, 0, 0) for h in self._beam]
            timings.update(region=0.0, edge=0.0, beam=0.0, proposals=0.0)
            timings["total"] = timings["prepare"] + 1e3 * (time.perf_counter() - t0)
            self.candidates, self.scored, self.lifted = [], [], None
            return _Frame(index, True, kept, self._cost - self._cost.min(), np.arange(len(kept)), 0, timings)
        if (begun is not None and begun.index == index and begun.prepared is prepared
                and begun.keypoints is keypoints):
            work, leading, t1 = begun.work, begun.leading, begun.started
        else:
            work = self._frame_work(prepared, keypoints)
            t1 = time.perf_counter()
            leading = work.submit(_timed_fit, self._beam[0].pose, cfg, cfg.evaluations)
        keypoint_cost = work.costs.keypoint
        # the lifter reads the keypoints under both labellings (a candidate pays its own's energy)
        lifted = self.lifting.lift(keypoints, self.camera, self.model) if self.lifting is not None else None
        lifted_swapped = (self.lifting.lift(keypoints.swapped(), self.camera, self.model)
                          if lifted is not None and keypoint_cost is not None else None)
        lifts = (lifted, lifted_swapped)
        # every other registration is scored on the thread that ran it, with the detector's
        # labels where it shows the person's front (None: no keypoints)
        front = None if keypoint_cost is None else self._front_price(keypoints)
        # the front evidence in use (the labelling term on): a leader reading it swapped is offered
        # the way back (the torso's flip refined, a beam place facing the other way)
        contested = bool(front) and cfg.labelling_weight > 0       # a front claim, priced
        score = functools.partial(self._scored, lifts=lifts, front=front)
        # what needs no leader runs beside it: the proposal stage (whose ranking this thread
        # waits for), the beam's other hypotheses
        proposed = []
        if self.sources and cfg.proposals_refined > 0:
            context = ProposalContext(lifted=lifted, lifted_swapped=lifted_swapped)
            rough = functools.partial(self._rough_unary, lifts=lifts, front=front)
            proposed = [self._propose(source, prepared, context, rough, score, work) for source in self.sources]
        tracked = [work.submit(_fit, score, h.pose, cfg, cfg.hypothesis_evaluations)
                   for h in self._beam[1:cfg.beam] if cfg.hypothesis_evaluations > 0]   # past the beam: mirrors
        leader, leader_s = leading.result()
        tracked.insert(0, work.submit(score, leader))
        share = (leader.region.evaluations if leader.region else 0) / max(leader.evaluations, 1)
        timings["region"] = 1e3 * leader_s * share
        timings["edge"] = 1e3 * leader_s - timings["region"]
        # what starts from the leader: each stage a task of its own, proposing and refining on
        # its thread (the heaviest first)
        stages: list[tuple[Future | _Done, str]] = []
        if cfg.recovery and leader.failed(cfg):
            stages.append((work.submit(_recover, score, self.last_good, cfg), "recovery"))
        if cfg.jumps:
            stages.append((work.submit(self._jump, score, leader.pose, contested), "jump"))
        if cfg.mirrors and keypoint_cost is not None:
            stages.append((work.submit(self._mirror, score, leader.pose), "mirror"))
        reaches = self._reaches(prepared, leader.pose, work) if cfg.hand_reacquisition else []
        if cfg.hand_reacquisition:     # its reaches spread over the threads, then one task ranks and refines
            proposals = [q for f in reaches for q in f.result()]      # reach_proposals' order
            stages.append((work.submit(_refine_lowest, score, proposals, cfg, cfg.hypothesis_evaluations)
                           if proposals else _Done(_Stage([], 0)), "reacquisition"))
        candidates: list[tuple[_Scored, str]] = [(f.result(), "tracked") for f in tracked]
        done = {origin: f.result() for f, origin in stages}
        for origin in ("recovery", "reacquisition", "jump", "mirror"):      # the candidates' order
            if origin in done:
                candidates += [(c, origin) for c in done[origin].candidates]
                work.evaluations += done[origin].evaluations
        t3 = time.perf_counter()
        for stage in proposed:
            candidates += [(f.result(), origin) for f, origin in stage.refined]
        evaluations = work.evaluations + sum(c.registration.evaluations for c, _ in candidates)
        timings["proposals"] = 1e3 * (sum(stage.seconds for stage in proposed) + time.perf_counter() - t3)
        t2 = t1 + leader_s
        terms = [c.terms for c, _ in candidates]
        hypotheses = [self._hypothesis(c.registration, origin, c.joints, c.terms, c.swapped) for c, origin in candidates]
        motion = transition_term([h.joints for h in self._beam], [h.joints for h in hypotheses],
                                 [h.pose[_HEADING] for h in self._beam], [h.pose[_HEADING] for h in hypotheses])
        motion_weight = self.weights[MOTION]
        transition = motion if motion_weight == 1.0 else motion_weight * motion
        cost, back = viterbi_step(self._cost, transition, np.array([h.unary for h in hypotheses]))
        for h, parent in zip(hypotheses, back):     # the heading on the circle (issue 44)
            h.pose = heading_near(h.pose, self._beam[parent].pose[_HEADING])
        self.candidates = [(h.origin, h.pose) for h in hypotheses]
        self.scored = [ScoredCandidate.from_terms(h.origin, h.pose, h.joints, t, motion[:, j], h.unary)
                       for j, (h, t) in enumerate(zip(hypotheses, terms))]
        self.lifted = lifted
        keep = self._select(hypotheses, cost, contested)
        timings["beam"] = 1e3 * (time.perf_counter() - t2)
        # from the frame's first work: its leader's start when begun early (the writing of the
        # last frame's results it overlapped counts as this frame's time)
        timings["total"] = timings["prepare"] + 1e3 * (time.perf_counter() - min(t0, t1))
        kept_cost = cost[keep]
        return _Frame(index, False, [hypotheses[k] for k in keep], kept_cost - kept_cost[0], back[keep], evaluations,
                      timings)

    def _frame_work(self, prepared, keypoints) -> "_FrameWork":
        """A frame's registrations: its region and edge costs and, when keypoints are given, the
        keypoint distance every registration adds, on this tracker's threads."""
        return _FrameWork(_FrameCosts(*self.costs(prepared), self.keypoint_cost(keypoints, prepared.labels)),
                          self._pool)

    def _front_price(self, keypoints: Keypoints) -> float:
        """The frame's front price (nats, :func:`~mocap.track.score.front_price`): 0 where the
        keypoints do not show the front; else priced by their shoulder distance (pixels) over the
        leader's shoulders seen square-on at their depth (``fx`` times their distance over their
        mean depth)."""
        if not keypoints.shows_front():
            return 0.0
        joints = self.model.joint_positions(self._beam[0].pose)
        right, left = joints[_R_SHOULDER], joints[_L_SHOULDER]
        square_on = self.camera.fx * float(np.linalg.norm(right - left)) / (0.5 * (right[2] + left[2]))
        seen = float(np.linalg.norm(keypoints.uv[_L_SHOULDER] - keypoints.uv[_R_SHOULDER]))
        return front_price(seen / square_on if square_on > 0 else math.nan)

    def _terms(self, region: float, edge: float, keypoint: float, pose: np.ndarray, joints: np.ndarray,
               lifted: LiftedHypotheses | None, front: float | None = None, swapped: bool = False) -> np.ndarray:
        """The values of a candidate's unary terms before their weights, shape (len(UNARY_TERMS),),
        :data:`~mocap.track.score.TERMS` order (see :class:`ScoredCandidate`; NaN: does not apply);
        ``front``: the frame's front price (:meth:`_front_price`; None: no keypoints), ``swapped``:
        the candidate reads them swapped."""
        cfg = self.config
        prior = self.prior.energy(pose) if self.prior is not None and cfg.prior_weight > 0 else math.nan
        lifter = self.lifting.energy(lifted, joints) if lifted is not None and cfg.lifter_weight > 0 else math.nan
        labelling = labelling_term(front, swapped) if cfg.labelling_weight > 0 else math.nan
        values = {"region": region, "edge": edge, "keypoint": keypoint, "prior": prior, "lifter": lifter,
                  "labelling": labelling}
        return np.array([values[t.name] for t in UNARY_TERMS], dtype=np.float64)

    def _scored(self, costs: "_FrameCosts", reg: Registration, *,
                lifts: tuple[LiftedHypotheses | None, LiftedHypotheses | None], front: float | None) -> "_Scored":
        """A registration's joints, the labelling its keypoint distance takes, and its unary
        terms (``lifts``, ``front``: as :meth:`_rough_unary`'s)."""
        joints = self.model.joint_positions(reg.pose)
        swapped = costs.keypoint is not None and costs.keypoint.labelling(reg.pose)
        terms = self._terms(reg.region_residual, reg.edge_residual, reg.keypoint_residual, reg.pose, joints,
                            lifts[swapped], front, swapped)
        return _Scored(reg, joints, bool(swapped), terms)

    def _rough_unary(self, costs: "_FrameCosts", pose: np.ndarray, *,
                     lifts: tuple[LiftedHypotheses | None, LiftedHypotheses | None], front: float | None) -> float:
        """The unary score of an unrefined pose (one evaluation of each cost): what ranks proposals.
        ``lifts``: the frame's lifted hypotheses under the detector's labelling and the swapped
        one; the pose pays the lifter energy and the labelling term of the labelling its keypoint
        distance takes; ``front``: the frame's front price (None: no keypoints)."""
        keypoint, swapped = (math.nan, False) if costs.keypoint is None else costs.keypoint.value_and_labelling(pose)
        return weighted_sum(self._terms(costs.region.evaluate_unchecked(pose), costs.edge(pose), keypoint, pose,
                                        self.model.joint_positions(pose), lifts[swapped], front, swapped),
                            self.weights)

    def _hypothesis(self, reg: Registration, origin: str, joints: np.ndarray, terms: np.ndarray,
                    swapped: bool) -> _Hypothesis:
        unary = weighted_sum(terms, self.weights)
        return _Hypothesis(reg.pose, joints, reg.region_residual, reg.edge_residual,
                           reg.edge_residual_after_region, reg.failed(self.config), origin, unary,
                           reg.region.iterations if reg.region else 0, reg.edge.iterations if reg.edge else 0,
                           bool(swapped))

    def _select(self, hypotheses: list[_Hypothesis], cost: np.ndarray, contested: bool = False) -> list[int]:
        """Indices of the survivors: cheapest path first, near-duplicates merged, at most ``beam``
        (on a ``contested`` frame whose leader reads the keypoints swapped, the last of them the
        cheapest facing the other way, when none of the others does); then the frame's mirrors
        not merged into them (the decoder's states of the mirrored branches, which the next frame
        does not register)."""
        keep: list[int] = []

        def merged(i) -> bool:
            joints = hypotheses[i].joints
            return any(np.linalg.norm(joints - hypotheses[k].joints, axis=1).mean() < MERGE_DISTANCE_M for k in keep)

        order = np.argsort(cost, kind="stable")
        for i in order:
            if merged(i):
                continue
            keep.append(int(i))
            if len(keep) == self.config.beam:
                break
        # the front/back ambiguity: where the detector shows the front and the leader reads it
        # swapped, the last place goes to the cheapest hypothesis facing the other way from the
        # leader, when none of the kept does (one side's branches cannot grow the other)
        if contested and len(keep) > 1 and hypotheses[keep[0]].swapped:
            facing = [math.cos(h.pose[_HEADING]) > 0.0 for h in hypotheses]
            if all(facing[k] == facing[keep[0]] for k in keep):
                other = next((int(i) for i in order if facing[i] != facing[keep[0]]
                              and hypotheses[i].origin != "mirror" and not merged(i)), None)
                if other is not None:
                    keep[-1] = other
        for i in order:
            if hypotheses[i].origin == "mirror" and int(i) not in keep and not merged(i):
                keep.append(int(i))
        return keep

    def _reaches(self, prepared, pose: np.ndarray, work: "_FrameWork") -> list[Future | _Done]:
        """Hand re-acquisition from the leader's ``pose`` (see :class:`TrackerConfig`): each
        unexplained skin region's reaches (:func:`~mocap.track.proposals.arm_reach_proposals`),
        one task a region and arm, in :func:`~mocap.track.proposals.reach_proposals`' order
        (none when no hand is left unexplained); the lowest-F reach is then refined."""
        joints = self.model.joint_positions(pose)
        targets = unexplained_hands(prepared.labels, joints, self.model, self.camera, self.config)
        if len(targets) == 0:
            return []
        return [work.submit(_arm_reaches, pose, joints, uv, side, reach_m, self.model, self.camera)
                for uv, side, reach_m in reach_jobs(pose, targets, self.model)]

    def _jump(self, costs: "_FrameCosts", score, pose: np.ndarray, contested: bool = False) -> "_Stage":
        """The kinematic jumps of the leader's ``pose``, the ``JUMPS_REFINED`` lowest-F ones
        refined and scored; and, on a ``contested`` frame (the detector shows the front, the
        labelling term on) whose leader reads the keypoints swapped, the torso's flip besides
        them, refined with ``hypothesis_evaluations``: a body turned round that the detector says
        faces the camera is offered the way back on every such frame (issue 49)."""
        cfg = self.config
        jumps = jump_proposals(pose, self.model)
        values = _region_values(costs, [q for _, q in jumps])
        chosen = [int(i) for i in np.argsort(values, kind="stable")[:JUMPS_REFINED]]
        budgets = [cfg.jump_evaluations] * len(chosen)
        flip = next(i for i, (name, _) in enumerate(jumps) if name == "torso_flip")
        if contested and flip not in chosen and costs.keypoint is not None and costs.keypoint.labelling(pose):
            chosen.append(flip)
            budgets.append(cfg.hypothesis_evaluations)
        return _Stage([_fit(costs, score, jumps[i][1], cfg, budget) for i, budget in zip(chosen, budgets)], len(jumps))

    def _mirror(self, costs: "_FrameCosts", score, pose: np.ndarray) -> "_Stage":
        """The converged leader's depth alternatives (:mod:`mocap.track.branches`), each registered
        with ``mirror_evaluations`` (0: its residuals where it stands) and scored."""
        return _Stage([_fit(costs, score, alternative.pose, self.config, self.config.mirror_evaluations)
                       for alternative in depth_alternatives(pose, self.model, self.camera)], 0)

    def _propose(self, source: ProposalSource, prepared, context: ProposalContext, rough, score,
                 work: "_FrameWork") -> "_Proposed":
        """One source's proposals: each given its unary score unrefined (``rough``), the
        ``proposals_refined`` lowest refined by a registration of ``proposal_evaluations``; with
        ``proposal_gate``, only those whose unrefined score is at most that many nats above the
        beam leader's pose's, unrefined on this frame (the last value ``rough`` gives)."""
        cfg = self.config
        t0 = time.perf_counter()
        proposals = source.propose(prepared, context)
        if not proposals:
            return _Proposed([], time.perf_counter() - t0)
        poses = [p.pose for p in proposals]
        if cfg.proposal_gate is not None:
            poses.append(self._beam[0].pose)
        values = work.submit(_rough_values, rough, poses).result()
        work.evaluations += 2 * len(poses)
        order = np.argsort(values[: len(proposals)], kind="stable")[: cfg.proposals_refined]
        if cfg.proposal_gate is not None:
            order = order[values[order] <= values[-1] + cfg.proposal_gate]
        refined = [(work.submit(_fit, score, proposals[int(i)].pose, cfg, cfg.proposal_evaluations),
                    proposals[int(i)].origin) for i in order]
        return _Proposed(refined, time.perf_counter() - t0)

    def close(self) -> None:
        """Stop the tracker's threads (none with ``threads=1``); it tracks on one thread after."""
        self._begun = None
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    # -- exact state -------------------------------------------------------------------------
    def state(self) -> dict[str, np.ndarray]:
        """Everything the next :meth:`push` and :meth:`finish` depend on, as named arrays.

        Restoring it with :meth:`restore` on a tracker built with the same model, camera and
        config makes the following calls give bit-identical results (floats are stored exactly).
        With smoothing on it holds the smoother's filtered state and, for each frame of the
        window, its label image, distance map and keypoints (``window_labels_<i>``,
        ``window_distance_<i>``, ``window_keypoints_<i>``: what the written pose's residuals are
        evaluated on; about 100 kB a frame at 160x120, so an offline run's state grows with the
        clip).
        """
        doc = {"beam": [_hyp_to_dict(h) for h in self._beam], "cost": self._cost.tolist(),
               "last_good": self.last_good.tolist(),
               "smoother": None if self.smoother is None else self.smoother.state(),
               "window": [{"index": f.index, "empty": f.empty, "hypotheses": [_hyp_to_dict(h) for h in f.hypotheses],
                           "cost": f.cost.tolist(), "back": f.back.tolist(), "evaluations": f.evaluations,
                           "timings": f.timings, "evidence": f.evidence is not None,
                           "keypoints": f.evidence is not None and f.evidence.keypoints is not None}
                          for f in self._window]}
        arrays = {"tracker_json": np.array(json.dumps(doc))}
        for i, f in enumerate(self._window):
            if f.evidence is not None:
                arrays[f"window_labels_{i}"], arrays[f"window_distance_{i}"] = f.evidence.labels, f.evidence.distance
                if f.evidence.keypoints is not None:
                    arrays[f"window_keypoints_{i}"] = f.evidence.keypoints
        return arrays

    def restore(self, state: dict[str, np.ndarray]) -> None:
        """Continue from a :meth:`state` (see there)."""
        try:
            doc = json.loads(str(np.asarray(state["tracker_json"])))
            beam = [_hyp_from_dict(h) for h in doc["beam"]]
            window = deque(_Frame(int(f["index"]), bool(f["empty"]), [_hyp_from_dict(h) for h in f["hypotheses"]],
                                  np.array(f["cost"], dtype=np.float64), np.array(f["back"], dtype=np.int64),
                                  int(f["evaluations"]), {k: float(v) for k, v in f["timings"].items()},
                                  _evidence_from(state, i, f))
                           for i, f in enumerate(doc["window"]))
            cost, last_good = np.array(doc["cost"], dtype=np.float64), check_pose(doc["last_good"])
            if (doc["smoother"] is None) != (self.smoother is None):
                raise ValueError("smoothing on in one, off in the other")
            if self.smoother is not None:
                self.smoother.restore(doc["smoother"])
        except (KeyError, TypeError, ValueError) as err:
            raise ValueError(f"not a tracker state of this version: {err}") from None
        self._beam, self._cost, self._window, self.last_good = beam, cost, window, last_good
        self._begun = None


@dataclass
class _FrameCosts:
    """One frame's costs as one thread uses them (their render buffers are its own)."""

    region: RegionCost
    edge: EdgeCost
    keypoint: KeypointCost | None       # None: no keypoints on the frame (or keypoint_weight 0)

    def spare(self) -> "_FrameCosts":
        """The same costs with buffers of their own, for another thread."""
        return _FrameCosts(self.region.spare(), self.edge.spare(), None if self.keypoint is None else self.keypoint.spare())


@dataclass
class _Begun:
    """A frame whose leader registration :meth:`Tracker.begin` started: the frame as given, its
    work, the leader's future (a registration and its seconds) and when it was started
    (``time.perf_counter()``)."""

    index: int
    prepared: PreparedFrame
    keypoints: Keypoints | None
    work: "_FrameWork"
    leading: Future
    started: float


class _Done:
    """A result computed at once on the calling thread (one thread): a future's ``result``."""

    def __init__(self, value) -> None:
        self._value = value

    def result(self):
        return self._value


class _FrameWork:
    """One frame's registrations and cost evaluations on the tracker's threads.

    :meth:`submit` runs ``task(costs, *args)`` at once on the calling thread when the tracker has
    no pool (``threads=1``), else on the pool; each task borrows a set of the frame's costs that
    no other task uses meanwhile (a spare is made when none is free: at most one per thread).
    Every task is a pure function of its arguments and the frame, so the results are the same,
    bit for bit, whatever thread ran them and in whatever order: the tracker reads them in the
    order it asked for them. ``evaluations`` counts the unrefined evaluations the tracker adds
    (the registrations count their own).
    """

    def __init__(self, costs: _FrameCosts, pool: ThreadPoolExecutor | None) -> None:
        self.costs, self.pool, self.evaluations = costs, pool, 0
        self._free: queue.SimpleQueue[_FrameCosts] = queue.SimpleQueue()
        self._free.put(costs)

    def submit(self, task, *args) -> Future | _Done:
        if self.pool is None:
            return _Done(task(self.costs, *args))
        return self.pool.submit(self._run, task, args)

    def _run(self, task, args):
        try:
            costs = self._free.get_nowait()
        except queue.Empty:
            costs = self.costs.spare()
        try:
            return task(costs, *args)
        finally:
            self._free.put(costs)


@dataclass
class _Stage:
    """A stage's scored candidates, in order, and the unrefined evaluations it spent (the
    registrations count their own)."""

    candidates: list["_Scored"]
    evaluations: int


@dataclass
class _Proposed:
    """One proposal source's refinements on a frame: (future registration, origin) pairs, and the
    seconds the calling thread spent proposing and ranking."""

    refined: list[tuple[Future | _Done, str]]
    seconds: float


@dataclass
class _Scored:
    """A candidate's registration, joints (10, 3; metres), keypoint labelling (swapped or not)
    and unary terms before their weights (:meth:`Tracker._terms`)."""

    registration: Registration
    joints: np.ndarray
    swapped: bool
    terms: np.ndarray


def _register(costs: _FrameCosts, start: np.ndarray, config: TrackerConfig, evaluations: int | None,
              step_scale: float = 1.0) -> Registration:
    """The frame's two-step registration from ``start`` with ``costs`` (see :func:`register`)."""
    return register(costs.region, costs.edge, start, config, evaluations=evaluations, step_scale=step_scale,
                    keypoint_cost=costs.keypoint)


def _fit(costs: _FrameCosts, score, start: np.ndarray, config: TrackerConfig, evaluations: int | None,
         step_scale: float = 1.0) -> _Scored:
    """:func:`_register`, scored by ``score(costs, registration)`` (:meth:`Tracker._scored`)."""
    return score(costs, _register(costs, start, config, evaluations, step_scale))


def _timed_fit(costs: _FrameCosts, start: np.ndarray, config: TrackerConfig,
               evaluations: int) -> tuple[Registration, float]:
    """:func:`_register` and the seconds it took."""
    t0 = time.perf_counter()
    reg = _register(costs, start, config, evaluations)
    return reg, time.perf_counter() - t0


def _region_values(costs: _FrameCosts, poses: list[np.ndarray]) -> np.ndarray:
    """F at each pose, shape (len(poses),)."""
    return np.array([costs.region.evaluate_unchecked(q) for q in poses])


def _rough_values(costs: _FrameCosts, rough, poses: list[np.ndarray]) -> np.ndarray:
    """``rough(costs, pose)`` (the unrefined unary score) at each pose, shape (len(poses),)."""
    return np.array([rough(costs, q) for q in poses])


def _arm_reaches(costs: _FrameCosts, pose: np.ndarray, joints: np.ndarray, uv: np.ndarray, side: str,
                 reach_m: float, model: BodyModel, camera: Camera) -> list[np.ndarray]:
    """:func:`~mocap.track.proposals.arm_reach_proposals` as a task (it needs no cost)."""
    return arm_reach_proposals(pose, joints, uv, side, reach_m, model, camera)


def _refine_lowest(costs: _FrameCosts, score, poses: list[np.ndarray], config: TrackerConfig,
                   evaluations: int) -> _Stage:
    """The pose of lowest F among ``poses`` refined by a registration of ``evaluations`` and
    scored: a stage that spent ``len(poses)`` unrefined evaluations."""
    start = poses[int(np.argmin(_region_values(costs, poses)))]
    return _Stage([_fit(costs, score, start, config, evaluations)], len(poses))


def _recover(costs: _FrameCosts, score, last_good: np.ndarray, config: TrackerConfig) -> _Stage:
    """Recovery: the last good pose registered with the full budget and a wider simplex, scored."""
    return _Stage([_fit(costs, score, last_good, config, None, RECOVERY_STEP_SCALE)], 0)


def _evidence_from(state: dict[str, np.ndarray], i: int, frame: dict) -> _Evidence | None:
    """Window frame ``i``'s evidence from a :meth:`Tracker.state` (None where it has none)."""
    if not frame["evidence"]:
        return None
    keypoints = np.array(state[f"window_keypoints_{i}"], dtype=np.float64) if frame["keypoints"] else None
    return _Evidence(np.array(state[f"window_labels_{i}"], dtype=np.uint8),
                     np.array(state[f"window_distance_{i}"], dtype=np.float32), keypoints)


def _read_as(keypoints: np.ndarray, swapped: bool) -> np.ndarray:
    """A frame's stored keypoints, shape (10, 3) (u, v pixels and the confidence), under the
    labelling a hypothesis read them with: left and right exchanged (:data:`SWAPPED_JOINTS`)
    when ``swapped``, else as the detector gave them."""
    return keypoints[list(SWAPPED_JOINTS)] if swapped else keypoints


def _hyp_to_dict(h: _Hypothesis) -> dict:
    return {"pose": h.pose.tolist(), "joints": h.joints.tolist(), "region": h.region_residual,
            "edge": h.edge_residual, "edge_after_region": h.edge_residual_after_region, "failed": h.failed,
            "origin": h.origin, "unary": h.unary, "region_iterations": h.region_iterations,
            "edge_iterations": h.edge_iterations, "swapped": h.swapped}


def _hyp_from_dict(d: dict) -> _Hypothesis:
    return _Hypothesis(np.array(d["pose"], dtype=np.float64), np.array(d["joints"], dtype=np.float64),
                       float(d["region"]), float(d["edge"]), float(d["edge_after_region"]), bool(d["failed"]),
                       str(d["origin"]), float(d["unary"]), int(d["region_iterations"]), int(d["edge_iterations"]),
                       bool(d["swapped"]))


def _result(frame: _Frame, k: int) -> FrameResult:
    h = frame.hypotheses[k]
    return FrameResult(frame=frame.index, pose=h.pose.copy(), joints=h.joints.copy(),
                       region_residual=h.region_residual, edge_residual=h.edge_residual,
                       edge_residual_after_region=h.edge_residual_after_region, failed=h.failed, empty=frame.empty,
                       origin=h.origin, evaluations=frame.evaluations, region_iterations=h.region_iterations,
                       edge_iterations=h.edge_iterations, timings_ms=dict(frame.timings), hypothesis=k, score=h.unary,
                       decoded_pose=h.pose.copy(), labels_swapped=h.swapped)


def proposal_sources(config: TrackerConfig, lifting: LifterSource | None = None) -> list[ProposalSource]:
    """The proposal stage's sources that ``config`` switches on: with ``lifter_weight`` > 0 the
    learned lifter's hypotheses of the frame's keypoints (``lifting``, or a new
    :class:`LifterSource` with the shipped lifter; it proposes nothing on frames without
    keypoints). It replaced the arms' one-at-a-time inverse kinematics on the keypoints (issue 29:
    docs/research-log.md)."""
    if not config.uses_lifter:
        return []
    return [lifting if lifting is not None else LifterSource(path=config.lifter_file)]


def track_prepared(prepared_frames, tracker: Tracker, *, first_index: int = 0, progress: bool = False,
                   description: str = "tracking") -> list[FrameResult]:
    """Track frames already prepared by :func:`mocap.imaging.prepare_frame` (in memory).

    Experiments reuse one image-side pass for many tracker settings this way.

    Parameters
    ----------
    prepared_frames : sequence of PreparedFrame
    tracker : Tracker
        Fresh, or continuing a stream; :meth:`Tracker.finish` is called at the end.

    Returns
    -------
    list of FrameResult
        One per frame, in order.
    """
    from tqdm import tqdm

    out: list[FrameResult] = []
    for i, p in enumerate(tqdm(prepared_frames, desc=description, unit="frame", disable=not progress)):
        out += tracker.push(first_index + i, p)
    return out + tracker.finish()
