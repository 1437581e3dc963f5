"""The image side: from a video frame to what the costs compare the model against.

* :func:`subtract_background` — foreground mask against an empty-scene image, robust to
  sensor noise and soft shadows (:func:`median_background` builds that image).
* :class:`ColourModel` — one Gaussian per colour class in HSV with circular hue;
  :func:`learn_colour_model` learns skin and clothes from the first frame
  (:func:`detect_face`); :meth:`ColourModel.classify` makes the label image.
* :func:`detect_edges` and :func:`distance_map` — edges in the dilated foreground and the
  truncated distance to them.
* :func:`prepare_frame` — all of it in one call, timed per stage, with :class:`ImagingConfig`.

Label images follow :mod:`mocap.labels`. :mod:`mocap.imaging.testing` makes synthetic scenes.
"""
from mocap.imaging._validate import Box, check_box
from mocap.imaging.background import clean_mask, median_background, subtract_background
from mocap.imaging.colour import ColourModel, detect_face, learn_colour_model, rgb_to_hsv
from mocap.imaging.config import ImagingConfig
from mocap.imaging.edges import detect_edges, distance_map
from mocap.imaging.prepare import PreparedFrame, prepare_frame

__all__ = [
    "check_box",
    "Box", "ColourModel", "ImagingConfig", "PreparedFrame", "clean_mask", "detect_edges",
    "detect_face", "distance_map", "learn_colour_model", "median_background", "prepare_frame",
    "rgb_to_hsv", "subtract_background",
]
