"""The names of the files a run writes (docs/design.md section 4): one table, read by every
module that writes or reads them (and by the tests).

A track run's folder (:func:`mocap.run.track`): :data:`POSES_CSV` (the journal), with keypoints
:data:`KEYPOINTS_CSV` (their journal),
:data:`POSES_BVH`, :data:`OVERLAY_MP4`, :data:`RUN_JSON`, :data:`COLOUR_MODEL_JSON`,
:data:`RESIDUALS_PNG`, the checkpoint :data:`STATE_FILE` (kept: a finished run's last state)
and the lock :data:`LOCK_FILE`, and while it runs :data:`OVERLAY_TMP`. A ``segment`` folder:
:data:`SEGMENT_JSON`, :data:`IMAGING_JSON`, :data:`SEGMENT_MP4`, the folders
:data:`SEGMENT_PICTURES` (and the colour model). The top of a ``track-many`` folder:
:data:`SUMMARY_CSV`, :data:`SUMMARY_PNG`, :data:`TRACK_MANY_JSON`. ``calibrate``'s default output
and ``demo --auto-calibrate``'s calibration: :data:`CALIBRATION_JSON`.
"""
from __future__ import annotations

from mocap.io.lock import LOCK_FILE

__all__ = ["CALIBRATION_JSON", "COLOUR_MODEL_JSON", "IMAGING_JSON", "KEYPOINTS_CSV", "LOCK_FILE", "OVERLAY_MP4",
           "OVERLAY_TMP", "POSES_BVH", "POSES_CSV", "RESIDUALS_PNG", "RUN_JSON", "RUN_OUTPUTS", "SEGMENT_JSON",
           "SEGMENT_MP4", "SEGMENT_PICTURES", "STATE_FILE", "SUMMARY_CSV", "SUMMARY_PNG", "TRACK_MANY_JSON"]

#: Pose, 3D and 2D joints and per-frame columns of every tracked frame, appended as frames are decided.
POSES_CSV = "poses.csv"
#: The 2D keypoints the tracker was given (a keypoint file, input pixels), appended as frames are
#: pushed, in a run with keypoints.
KEYPOINTS_CSV = "keypoints.csv"
#: The poses as BVH motion (degrees), written at the end.
POSES_BVH = "poses.bvh"
#: The video with the registered model drawn on it.
OVERLAY_MP4 = "overlay.mp4"
#: The overlay while it is written (moved to :data:`OVERLAY_MP4` when whole).
OVERLAY_TMP = ".overlay.tmp.mp4"
#: Settings, versions, timings, metrics: ``status: running`` at the start, everything at the end.
RUN_JSON = "run.json"
#: The colour classes the run learnt (or was given).
COLOUR_MODEL_JSON = "colour_model.json"
#: Both residuals per frame with their failure thresholds.
RESIDUALS_PNG = "residuals.png"
#: The checkpoint: the tracker's exact state and the journals' lengths it belongs to.
STATE_FILE = ".tracker_state.npz"
#: ``python -m mocap segment``'s settings.
SEGMENT_JSON = "segment.json"
#: ``segment``'s imaging parameters (:class:`mocap.imaging.ImagingConfig`).
IMAGING_JSON = "imaging.json"
#: ``segment``'s video: frame | labels / edges | distance.
SEGMENT_MP4 = "segment.mp4"
#: ``segment``'s folders of per-frame PNGs: label images, edge masks, distance maps.
SEGMENT_PICTURES = ("labels", "edges", "distance")
#: A calibration (:mod:`mocap.calibrate`): ``demo --auto-calibrate``'s, in its output folder (and
#: ``calibrate``'s default ``--out``, spelled in its parser, which imports no run module).
CALIBRATION_JSON = "calibration.json"
#: ``track-many``: one row per input; a plot of it; the options of the folder's videos.
SUMMARY_CSV, SUMMARY_PNG, TRACK_MANY_JSON = "summary.csv", "summary.png", "track-many.json"
#: What a finished track run leaves in its folder for people (with an overlay); besides them,
#: hidden, :data:`STATE_FILE` and :data:`LOCK_FILE` (:mod:`mocap.io.lock`).
RUN_OUTPUTS = (POSES_CSV, POSES_BVH, OVERLAY_MP4, RUN_JSON, COLOUR_MODEL_JSON, RESIDUALS_PNG)
