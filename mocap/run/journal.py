"""The run's journal and checkpoint: ``poses.csv`` rows appended as frames are decided,
``keypoints.csv`` rows (the 2D keypoints the tracker was given, a keypoint file of
:mod:`mocap.io.keypoints`) as frames are pushed, and every :data:`CHECKPOINT_EVERY` frames the
tracker's exact state with the lengths of both journals it belongs to (:mod:`mocap.io.checkpoint`),
for resumes bit for bit the same.

What a crash leaves behind: the journals' rows (the last of each maybe half written) and the
last checkpoint (written atomically after the rows it covers are synced); a resumed run cuts the
journals back to the checkpoint's lengths and goes on from its state (:func:`previous_run`).
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mocap.calibrate import Calibration
from mocap.imaging import ColourModel
from mocap.io.checkpoint import (Checkpoint, cut_journal, read_checkpoint, synced_length, truncate_journal,
                                  write_checkpoint)
from mocap.io.keypoints import Keypoints, append_keypoints
from mocap.io.pose_table import PoseTable
from mocap.run import files

__all__ = ["CHECKPOINT_EVERY", "KEYPOINTS_FILE", "SETTINGS_FORMAT", "STATE_FILE", "Journal", "People",
           "other_settings", "previous_run"]

#: Frames between two checkpoints (and after the last frame of a file): a resumed run redoes at
#: most this many frames (the journal is cut back to the checkpoint), bit for bit the same.
CHECKPOINT_EVERY = 25
#: Checkpoint (:mod:`mocap.io.checkpoint`): the tracker's exact state after the last pushed
#: frame and the lengths of ``poses.csv`` and ``keypoints.csv`` that go with it, for bit-identical
#: resumes (:data:`mocap.run.files.STATE_FILE`).
STATE_FILE = files.STATE_FILE
#: The keypoint journal: every pushed frame's keypoints (input pixels), when the run has keypoints
#: (:data:`mocap.run.files.KEYPOINTS_CSV`).
KEYPOINTS_FILE = files.KEYPOINTS_CSV
#: Checkpoint entry holding the keypoint journal's length in bytes.
KEYPOINTS_BYTES = "run_keypoints_bytes"
#: Checkpoint entry holding the people's bookkeeping (:class:`People`, JSON text).
PEOPLE = "run_people"
#: Checkpoint entry holding ``(frame, dark)`` of the frames the tracker still holds back.
PENDING_DARK = "run_pending_dark"
#: ``run.json`` ``settings.format``: the settings' layout. A run of an earlier layout (none: each
#: option said once, the background's mode in the options' words since ``mocap-run-2``) is not
#: resumed (:func:`other_settings` says so in one line); its finished ``run.json`` still reads
#: (:meth:`mocap.run.accounts.SetupAccount.from_settings`).
SETTINGS_FORMAT = "mocap-run-2"
#: Frames in a row with nobody in view after which the tracked person has left: the next person
#: seen is calibrated afresh (:class:`mocap.run.person.NewcomerFinder`).
PERSON_GONE_FRAMES = 10


@dataclass
class People:
    """Who was tracked when: the run's segments, one per person (``run.json`` ``segments``).

    Attributes
    ----------
    segments : list of dict
        ``first_frame``, ``last_frame`` (None while open), the person's ``calibration``, their
        ``colour_classes`` and how they were ``found`` (None for the first).
    absent : int
        Frames in a row with nobody in view.
    last_seen : int
        The last frame with someone in view.
    vacant : bool
        The person left (:data:`PERSON_GONE_FRAMES` empty frames): the next one seen starts a
        segment.
    """

    segments: list[dict] = field(default_factory=list)
    absent: int = 0
    last_seen: int = -1
    vacant: bool = False

    @classmethod
    def first(cls, start_frame: int, calibration: Calibration, colour_model: ColourModel) -> "People":
        """The bookkeeping of a run starting at ``start_frame`` with one person."""
        people = cls(last_seen=start_frame - 1)
        people.begin(start_frame, calibration, colour_model, None)
        return people

    @property
    def segment(self) -> int:
        """The current segment's number (column ``segment`` of ``poses.csv``)."""
        return len(self.segments) - 1

    def begin(self, first_frame: int, calibration: Calibration, colour_model: ColourModel,
              found: dict | None) -> None:
        """A new person from ``first_frame`` (``found``: how they were found)."""
        self.vacant = False
        self.segments.append({"first_frame": int(first_frame), "last_frame": None,
                              "calibration": calibration.to_dict(), "colour_classes": list(colour_model.names),
                              "found": found})

    def saw(self, index: int, empty: bool) -> None:
        """Frame ``index`` was empty or showed someone: after :data:`PERSON_GONE_FRAMES` empty
        frames in a row the person (seen in this segment) has left."""
        if not empty:
            self.absent, self.last_seen = 0, index
            return
        self.absent += 1
        seen = self.last_seen >= self.segments[-1]["first_frame"]
        if self.absent == PERSON_GONE_FRAMES and seen and not self.vacant:
            self.vacant = True
            self.segments[-1]["last_frame"] = self.last_seen

    def close(self) -> None:
        """The run ended: the open segment ends at the last frame with someone."""
        if not self.vacant:
            self.segments[-1]["last_frame"] = self.last_seen

    def to_array(self) -> np.ndarray:
        """The checkpoint's entry (JSON text)."""
        return np.array(json.dumps({"segments": self.segments, "absent": self.absent, "last_seen": self.last_seen,
                                    "vacant": self.vacant}))

    @classmethod
    def from_array(cls, value: np.ndarray) -> "People":
        data = json.loads(str(value))
        return cls(data["segments"], data["absent"], data["last_seen"], data["vacant"])


@dataclass
class Journal:
    """``poses.csv``, ``keypoints.csv`` and their checkpoint in an output folder.

    Attributes
    ----------
    path : Path
        ``poses.csv``.
    state_path : Path
        The checkpoint (:data:`STATE_FILE`).
    keypoints_path : Path
        ``keypoints.csv`` (:data:`KEYPOINTS_FILE`).
    """

    path: Path
    state_path: Path
    keypoints_path: Path

    @classmethod
    def in_folder(cls, out_dir: Path) -> "Journal":
        return cls(out_dir / files.POSES_CSV, out_dir / STATE_FILE, out_dir / KEYPOINTS_FILE)

    def append(self, row: PoseTable) -> None:
        """A decided frame's row (synced with the next checkpoint)."""
        row.append_to(self.path, sync=False)

    def append_keypoints(self, index: int, keypoints: Keypoints) -> None:
        """A pushed frame's keypoints, input pixels (synced with the next checkpoint)."""
        append_keypoints(self.keypoints_path, index, keypoints)

    def checkpoint(self, tracker_state: dict, dark: dict[int, bool], people: People, next_index: int) -> None:
        """The tracker's state, the held-back frames' dark flags and the people, with the journal
        length they belong to; frames before ``next_index`` are done."""
        pending = np.array(sorted(dark.items()), np.int64).reshape(-1, 2)
        keypoint_bytes = np.int64(synced_length(self.keypoints_path))
        write_checkpoint(self.state_path, {**tracker_state, PENDING_DARK: pending, PEOPLE: people.to_array(),
                                           KEYPOINTS_BYTES: keypoint_bytes}, next_index, self.path)


@dataclass
class Resumed:
    """A checkpoint taken apart (:meth:`split`): the tracker's state, the dark flags of the
    frames it held back and the people."""

    checkpoint: Checkpoint
    tracker_state: dict
    dark: dict[int, bool]
    people: People | None

    @classmethod
    def split(cls, checkpoint: Checkpoint) -> "Resumed":
        state = dict(checkpoint.state)
        pending = state.pop(PENDING_DARK, np.zeros((0, 2), np.int64))
        people = state.pop(PEOPLE, None)
        state.pop(KEYPOINTS_BYTES, None)
        return cls(checkpoint, state, {int(f): bool(v) for f, v in pending},
                   None if people is None else People.from_array(people))


def previous_run(journal: Journal, run_json: Path, settings: dict, overwrite: bool) -> Checkpoint | None:
    """The checkpoint to resume from (the journal cut back to it), or None to start afresh.

    Raises
    ------
    ValueError
        The folder holds a run with other settings (or no ``run.json``): one line saying which
        (:func:`other_settings`).
    """
    if overwrite or not (journal.path.exists() or journal.state_path.exists()):
        for path in (journal.path, journal.state_path, journal.keypoints_path):
            path.unlink(missing_ok=True)
        return None
    try:
        previous = json.loads(run_json.read_text()) if run_json.exists() else {}
    except json.JSONDecodeError:
        previous = {}
    wanted = json.loads(json.dumps(settings))
    if previous.get("settings") != wanted:
        raise ValueError(other_settings(journal.path.parent, previous.get("settings"), wanted))
    checkpoint = read_checkpoint(journal.path.parent / STATE_FILE)
    truncate_journal(journal.path, checkpoint)   # rows after the checkpoint (and a partial line) are redone
    keypoint_bytes = None if checkpoint is None else checkpoint.state.get(KEYPOINTS_BYTES)
    if checkpoint is not None and keypoint_bytes is None and settings.get("keypoints") != "none":
        raise ValueError(f"{journal.path.parent} holds a run of an earlier mocap (its checkpoint has no keypoint "
                         "journal), which cannot be resumed exactly: start afresh with --overwrite or use another "
                         "--out")
    cut_journal(journal.keypoints_path, 0 if keypoint_bytes is None else int(keypoint_bytes))
    return checkpoint


def other_settings(folder: Path, held: dict | None, wanted: dict) -> str:
    """Why ``folder``'s run (``run.json`` ``settings``: ``held``) is not resumed with ``wanted``,
    and what to do, in one line: no ``run.json``; a run of an earlier mocap (no
    ``settings.keypoints``); other keypoints (``--keypoints`` changed, or the optional extra
    ``keypoints`` installed or removed under ``auto``); a run of an earlier layout
    (:data:`SETTINGS_FORMAT`); else the settings that differ."""
    what = "start afresh with --overwrite or use another --out"
    if not isinstance(held, dict):
        return f"{folder} holds a run without a readable run.json: {what}"
    if "keypoints" not in held:
        return (f"{folder} holds a run of an earlier mocap (its run.json has no settings.keypoints), which cannot be "
                f"resumed exactly: {what}")
    if held.get("format") != wanted.get("format"):
        laid = "no settings.format" if held.get("format") is None else f"settings.format {held['format']!r}"
        return (f"{folder} holds a run of an earlier mocap (its run.json has {laid}, this mocap writes "
                f"{wanted.get('format')!r}), which cannot be resumed: {what}")
    if held["keypoints"] != wanted.get("keypoints"):
        return (f"{folder} holds a run tracked with keypoints from {held['keypoints']!r}, this run's would come from "
                f"{wanted.get('keypoints')!r} (--keypoints changed, or the optional extra 'keypoints' was installed or "
                f"removed since): resume it with the keypoints it had, or {what}")
    differ = sorted(key for key in held.keys() | wanted.keys() if held.get(key) != wanted.get(key))
    return f"{folder} holds a run with other settings ({', '.join(differ)}): {what}"
