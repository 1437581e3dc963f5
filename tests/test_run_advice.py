"""The run's last words: one line on what to try when most frames failed (the options not used
yet), and the overlay's size (the input's, at most 1280 pixels wide)."""
import pytest

from mocap.render import Camera
from mocap.run.advice import KEYPOINTS_EXTRA_INSTALL, RunFacts, what_to_try
from mocap.run.overlay import OverlayGeometry


def test_a_run_that_went_well_gets_no_advice():
    assert what_to_try(RunFacts(frames=20, failures=10, keypoints_extra=False, background="auto",
                                calibration="automatic")) is None
    assert what_to_try(RunFacts(frames=0, failures=0, keypoints_extra=False)) is None


def test_advice_names_only_what_was_not_tried_in_one_line():
    line = what_to_try(RunFacts(frames=20, failures=20, keypoints_extra=True, background="none",
                                calibration="automatic"))
    assert line.startswith("20 of 20 frames were marked failed") and "\n" not in line
    assert all(option in line for option in ("--keypoints mediapipe", "--background IMG", "--height M"))
    tried = what_to_try(RunFacts(frames=20, failures=11, keypoints="mediapipe", keypoints_extra=True, background="image",
                                 height_given=True, calibration="automatic"))
    assert not any(option in tried for option in ("--keypoints", "--background", "--height", "extra"))
    given = what_to_try(RunFacts(frames=4, failures=3, keypoints_extra=True, background="auto",
                                 calibration="given"))
    assert "--height" not in given and "--keypoints mediapipe" in given
    from_file = what_to_try(RunFacts(frames=4, failures=3, keypoints="points.csv", keypoints_extra=False,
                                     background="image", calibration="given"))
    assert "keypoints" not in from_file


def test_without_the_keypoints_extra_the_advice_names_it_first():
    """A newcomer's default install (no extra, ``--keypoints auto`` found none): the line says
    how to install the extra, before any option; with the extra installed it names the option."""
    facts = dict(frames=65, failures=41, keypoints=None, background="auto", calibration="automatic")
    without = what_to_try(RunFacts(**facts, keypoints_extra=False))
    assert without == ('41 of 65 frames were marked failed; try the keypoints extra (python -m pip install -e '
                       '".[keypoints]": MediaPipe Pose\'s 2D keypoints as a further cue, used by default once '
                       'installed), or a background plate (--background IMG, a picture of the empty scene, or '
                       '--background-frames A:B where nobody is in view), or --height M (the person\'s height fixes '
                       'the scale of the automatic calibration)')
    assert KEYPOINTS_EXTRA_INSTALL in without and "--keypoints" not in without
    installed = what_to_try(RunFacts(**facts, keypoints_extra=True))
    assert installed.startswith("41 of 65 frames were marked failed; try --keypoints mediapipe (2D keypoints")
    assert "extra" not in installed
    with pytest.raises(TypeError):
        RunFacts(65, 41)                    # keyword-only


@pytest.mark.parametrize("width, height, work, factor", [(640, 480, 4, 1), (2560, 1440, 16, 2), (1280, 720, 8, 1)])
def test_overlay_is_drawn_at_the_input_size_up_to_1280_wide(width, height, work, factor):
    full = Camera.default(width, height)
    geometry = OverlayGeometry.of(full.working(width, height, work), work, width, height)
    expected = full.working(width, height, factor)       # hand: the input reduced by the integer factor
    assert geometry.factor == factor and geometry.camera.shape == (height // factor, width // factor)
    assert (geometry.camera.fx, geometry.camera.cx) == pytest.approx((expected.fx, expected.cx))
