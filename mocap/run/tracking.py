"""The one entry point: :func:`track` turns a source (a video file, an image folder, a sequence
folder or a live camera) into a run's files, from :class:`~mocap.run.options.OwnVideoOptions`.

It opens the source (:class:`RunInput`: a sequence folder's own background, calibration,
ground truth and frame rate are used when the options give none), resolves the options once
(:class:`mocap.run.options.RunChoices`: which keypoints run and why, the colours' source, the
background's mode: what the rest reads), decides the set-up once
(:func:`mocap.run.setup.find_setup`) and runs the loop (:func:`mocap.run.loop.track_frames`).
"""
from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from mocap._progress import compiling_announced
from mocap.calibrate import Calibration
from mocap.imaging.resample import working_factor
from mocap.io import mediapipe_keypoints
from mocap.io.frames import CameraSource, VideoSource
from mocap.io.sequence import find_sequence
from mocap.io.video import read_image
from mocap.run.advice import RunFacts, mostly_failed, what_to_try
from mocap.run.loop import RunParams, track_frames
from mocap.run.options import OwnVideoOptions, RunChoices
from mocap.run.outputs import RunSummary
from mocap.run.person import NewcomerFinder
from mocap.run.accounts import SetupAccount
from mocap.run.setup import SetupRequest, find_setup

__all__ = ["RunInput", "track"]


@dataclass(frozen=True, eq=False)
class RunInput:
    """A source opened for a run, with the files it brings or the options name.

    Attributes
    ----------
    frames : VideoSource or CameraSource
        :mod:`mocap.io.frames`.
    background : str or None
        Image of the empty scene (the options' or a sequence folder's).
    sequence_background : bool
        ``background`` is the sequence folder's own.
    calibration : str or None
        ``calibration.json`` (the options' or a sequence folder's).
    ground_truth : str or None
    fps : float, frames per second
    """

    frames: VideoSource | CameraSource
    background: str | None
    sequence_background: bool
    calibration: str | None
    ground_truth: str | None
    fps: float

    @classmethod
    def open(cls, source, options: OwnVideoOptions) -> "RunInput":
        """Open ``source``; FileNotFoundError for a named file that is missing."""
        if getattr(source, "live", False):
            if options.background_frames is not None:
                raise ValueError("background frames need a video file, not a live camera")
            _check_files(options.background, options.calibration)
            return cls(source, options.background, False, options.calibration, options.ground_truth,
                       source.fps or 25.0)
        seq = find_sequence(source)
        own_background = seq.background if not options.no_background and options.background_frames is None else None
        background = options.background or own_background
        calibration = options.calibration or seq.calibration
        _check_files(background, calibration)
        frames = VideoSource(seq.frames, fps=seq.fps() if seq.meta is not None else None)
        fps = (seq.fps(frames.fps or 25.0) if seq.meta is not None else frames.fps) or 25.0
        return cls(frames, background, own_background is not None, calibration,
                   options.ground_truth or seq.ground_truth, fps)

    def request(self, options: OwnVideoOptions, choices: RunChoices, progress: bool) -> SetupRequest:
        """What the set-up is told: the options as ``choices`` resolved them, the calibration
        rescaled to the working size."""
        width, height = self.frames.width, self.frames.height
        factor = None if options.work_width is None else working_factor(width, height, options.work_width)
        given = None
        if self.calibration is not None:
            given = Calibration.from_json(self.calibration)
            factor = factor or working_factor(width, height)
            given = dataclasses.replace(given, camera=given.camera.working(width, height, factor))
        return SetupRequest(factor=factor, background_mode=choices.background_mode,
                            background_image=read_image(self.background) if self.background else None,
                            background_frames=options.background_frames, calibration=given,
                            hfov_deg=options.hfov_deg, height_m=options.height_m, progress=progress,
                            keypoints=choices.keypoint_source)


def _check_files(background: str | None, calibration: str | None) -> None:
    """FileNotFoundError for a named background or calibration file that is missing."""
    for what, path in (("background", background), ("calibration", calibration)):
        if path is not None and not Path(path).is_file():
            raise FileNotFoundError(f"{what} file not found: {path}")


def track(source, out_dir: str | Path, options: OwnVideoOptions | None = None, *, progress: bool = True,
          on_setup: Callable[[SetupAccount], None] | None = None) -> RunSummary:
    """Track a video: set-up from the video (or as given), then the run.

    Parameters
    ----------
    source : str, Path or CameraSource
        A video file, a folder of images, a sequence folder (its ``background.png``,
        ``calibration.json``, ``ground_truth.csv`` and ``meta.json`` frame rate are used when
        ``options`` give none), or a live :class:`mocap.io.frames.CameraSource`.
    out_dir : str or Path
        Output folder (:func:`mocap.run.loop.track_frames`; an unfinished run there resumes).
    options : OwnVideoOptions, optional
    progress : bool
        Progress bars.
    on_setup : callable, optional
        Called with the set-up's account (:class:`mocap.run.accounts.SetupAccount`: ``run.json``
        ``settings.own_video``, the input and working sizes and the keypoints' line) before the first frame is
        tracked (the CLI prints it).

    Returns
    -------
    RunSummary
        ``setup`` is the account given to ``on_setup``; ``advice`` one line on what to try
        when most frames failed (:func:`mocap.run.advice.what_to_try`).

    Raises
    ------
    ValueError, FileNotFoundError
        Bad options (``colour="face"`` where the set-up learns the colours itself:
        :meth:`~mocap.run.options.RunChoices.check_colour`), missing files, a damaged video, no
        usable frame (one sentence each).
    """
    options = OwnVideoOptions() if options is None else options
    opened = RunInput.open(source, options)
    frames_in = opened.frames
    choices = None
    try:
        choices = RunChoices.of(options, opened.sequence_background)     # a bad keypoint file stops here
        with compiling_announced(progress, "the set-up's kernels"):
            found = find_setup(frames_in, opened.request(options, choices, progress))
        choices.check_colour(found.setup.colour_model is not None, found.setup.record.calibration_from, frames_in.live)
        if frames_in.live:
            frames_in.hold(found.consumed)
        setup = dataclasses.replace(found.setup, colour_from=choices.colour,
                                    background_file=Path(opened.background) if opened.background else None,
                                    record=dataclasses.replace(found.setup.record, keypoints=choices.keypoints_line))
        width, height = frames_in.width, frames_in.height
        account = dataclasses.replace(setup.record, input_width=width, input_height=height,
                                      working_width=setup.calibration.camera.width,
                                      working_height=setup.calibration.camera.height)
        if on_setup is not None:
            on_setup(account)
        newcomer = NewcomerFinder.of(setup, width, height, hfov_deg=options.hfov_deg, height_m=options.height_m)
        params = RunParams(options=options, choices=choices, ground_truth=opened.ground_truth, fps=opened.fps,
                           progress=progress, newcomer=newcomer)
        summary = track_frames(frames_in, setup, out_dir, params)
    finally:
        if choices is not None:
            choices.close()         # the detector's process
        if not frames_in.live:
            frames_in.close()       # the damage check's ffmpeg, when the run ended before it did
    used = choices.keypoint_cue
    # whether the extra is installed matters only to advice on a run without keypoints (its import takes ~2 s)
    extra = used is not None or (mostly_failed(summary.frames, summary.failures) and mediapipe_keypoints.available())
    facts = RunFacts(frames=summary.frames, failures=summary.failures, keypoints=used, keypoints_extra=extra,
                     background=account.background_mode, height_given=options.height_m is not None,
                     calibration=account.calibration_from)
    return dataclasses.replace(summary, setup=account, advice=what_to_try(facts))
