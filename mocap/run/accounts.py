"""How a run's set-up was found, as typed records: the background's and the calibration's
accounts and the set-up's (``run.json`` ``settings.own_video``; a newcomer's ``segments[].found``).

:mod:`mocap.run.setup` writes them, :mod:`mocap.run.person` writes a newcomer's, the outputs
read them back (:meth:`SetupAccount.from_settings`); this module imports neither, so neither
imports the other for them.
"""
from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["BackgroundAccount", "CalibrationAccount", "SetupAccount"]


@dataclass(frozen=True, kw_only=True)
class BackgroundAccount:
    """How the background was found (``run.json`` ``settings.own_video.background``).

    Attributes
    ----------
    mode : {"auto", "image", "frames", "none"}
        The mode asked for, in the options' own words (:data:`mocap.run.options.BACKGROUND_MODES`).
    used : bool
        A background image is subtracted: always for ``image`` and ``frames``, never for
        ``none``; for ``auto``, the estimate when the person moves enough
        (:func:`mocap.run.setup.choose_background`; a live camera has no clip to estimate from).
    reason : str
        Why, in words.
    details : dict
        What the choice rests on, JSON-ready: ``frames`` ``[A, B]`` (mode ``frames``), or
        ``sample_frames`` and ``evidence`` (an estimate, used or not).
    """

    mode: str
    used: bool
    reason: str
    details: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"mode": self.mode, "used": self.used, **self.details, "reason": self.reason}

    @classmethod
    def from_dict(cls, data: dict) -> "BackgroundAccount":
        """From ``settings.own_video.background``; a run.json written before the mode took the
        options' words (``estimated``, no ``used``) reads as ``auto``."""
        details = {k: v for k, v in data.items() if k not in ("mode", "used", "reason")}
        mode, used = data["mode"], data.get("used")
        if used is None:            # the earlier layout: the outcome as the mode
            used = mode in ("image", "frames", "estimated")
            mode = "auto" if mode == "estimated" or "sample_frames" in details else mode
        return cls(mode=mode, used=bool(used), reason=data["reason"], details=details)


@dataclass(frozen=True, kw_only=True)
class CalibrationAccount:
    """Where the calibration came from (``run.json`` ``settings.own_video.calibration``; a
    newcomer's ``segments[].found`` without ``source``).

    Attributes
    ----------
    source : {"given", "automatic"}
        (JSON ``from``.)
    frame : int or None
        The frame calibrated on (automatic).
    face_input_px : list of int or None, input pixels
        The face found there (``x0, y0, x1, y1`` as :class:`mocap.imaging.Box`), None without one.
    depth_m : float or None, metres
        The person's distance found (the initial pose's depth, 3 decimals).
    """

    source: str
    frame: int | None = None
    face_input_px: list[int] | None = None
    depth_m: float | None = None

    def to_dict(self, source: bool = True) -> dict:
        """JSON-ready (``source``: with ``from``, as in ``settings.own_video``; without, as a
        newcomer's ``found``)."""
        if self.source == "given":
            return {"from": "given"}
        found = {"frame": self.frame, "face_input_px": self.face_input_px, "depth_m": self.depth_m}
        return {"from": self.source, **found} if source else found

    @classmethod
    def from_dict(cls, data: dict) -> "CalibrationAccount":
        return cls(source=data["from"], frame=data.get("frame"), face_input_px=data.get("face_input_px"),
                   depth_m=data.get("depth_m"))


@dataclass(frozen=True, kw_only=True)
class SetupAccount:
    """How the set-up was found: what was chosen and why (:func:`mocap.run.setup.find_setup`;
    the ``on_setup`` of :func:`mocap.run.track` prints it; ``RunSummary.setup``).

    :meth:`to_dict` is ``run.json`` ``settings.own_video``: what is said nowhere else in
    ``settings`` (the working factor and the sizes are ``settings.working_resolution``'s, the
    keypoints ``settings.keypoints``).

    Attributes
    ----------
    hfov_deg : float, degrees
        The camera's horizontal field of view (without a calibration).
    height_m : float or None, metres
        The person's stature as given.
    background : BackgroundAccount
    working_factor : int
        Input pixels per working pixel.
    calibration : CalibrationAccount
    keypoints : str or None
        What keypoints run and why, as printed (:func:`mocap.run.options.resolve_keypoints`);
        None: not said (a set-up found outside :func:`mocap.run.track`, or read back).
    input_width, input_height, working_width, working_height : int or None, pixels
        The input's and the working frames' sizes (:func:`mocap.run.track` fills them).
    """

    hfov_deg: float
    height_m: float | None
    background: BackgroundAccount
    working_factor: int
    calibration: CalibrationAccount
    keypoints: str | None = None
    input_width: int | None = None
    input_height: int | None = None
    working_width: int | None = None
    working_height: int | None = None

    @property
    def background_mode(self) -> str:
        """:attr:`BackgroundAccount.mode`."""
        return self.background.mode

    @property
    def calibration_from(self) -> str:
        return self.calibration.source

    def to_dict(self) -> dict:
        """``run.json`` ``settings.own_video``, JSON-ready."""
        return {"hfov_deg": self.hfov_deg, "height_m": self.height_m, "background": self.background.to_dict(),
                "calibration": self.calibration.to_dict()}

    @classmethod
    def from_settings(cls, settings: dict) -> "SetupAccount | None":
        """From ``run.json`` ``settings`` (``own_video`` and ``working_resolution``), None
        without ``own_video``; a run.json of the earlier layout (``own_video`` with its own
        ``working_factor`` and ``keypoints``, the background's outcome as its mode) reads the same."""
        own = settings.get("own_video")
        if own is None:
            return None
        sizes = settings["working_resolution"]
        return cls(hfov_deg=own["hfov_deg"], height_m=own["height_m"],
                   background=BackgroundAccount.from_dict(own["background"]), working_factor=sizes["factor"],
                   calibration=CalibrationAccount.from_dict(own["calibration"]),
                   input_width=sizes["input_width"], input_height=sizes["input_height"],
                   working_width=sizes["width"], working_height=sizes["height"])
