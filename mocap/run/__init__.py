"""The run floor: a source in, a run's files out (docs/design.md sections 1, 3-4).

:func:`track` (``mocap.run.track(source, out, options)``) is the one entry point every caller
uses: the commands ``track``, ``track-many``, ``demo``, ``bench``, the experiments and the
notebooks. One module a job:

- :mod:`~mocap.run.files`    the names of the files a run writes (one table)
- :mod:`~mocap.run.options`  what a person may set (:class:`OwnVideoOptions`), the background's mode
- :mod:`~mocap.run.setup`    working resolution, background, calibration, decided once
- :mod:`~mocap.run.accounts` how the set-up was found (``run.json`` ``settings.own_video``)
- :mod:`~mocap.run.person`   finding and calibrating a person on one frame, newcomers
- :mod:`~mocap.run.colours`  the colour classes, learnt in one place
- :mod:`~mocap.run.loop`     the run loop: reader thread, tracker, people, damage verdict
- :mod:`~mocap.run.journal`  ``poses.csv`` and the checkpoint (bit-identical resumes)
- :mod:`~mocap.run.outputs`  ``poses.bvh``, ``residuals.png``, ``run.json``
- :mod:`~mocap.run.overlay`  ``overlay.mp4`` on the input's own frames
- :mod:`~mocap.run.advice`   one line on what to try when most frames failed
- :mod:`~mocap.run.many`     many videos on a Dask cluster (``track-many``)
- :mod:`~mocap.run.segment`  what the image side sees (``segment``)

Frame-level control (push one prepared frame at a time, look at the beam) is the tracker's
API, :class:`mocap.track.Tracker`, which ``experiments/units.py`` and ``ambiguity.py`` use.
"""
from mocap.run.options import OwnVideoOptions
from mocap.run.outputs import RunSummary
from mocap.run.tracking import track

__all__ = ["OwnVideoOptions", "RunSummary", "track"]
