"""Working resolution, background estimated from a clip, the scene's colours."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi
from skimage.transform import downscale_local_mean

from mocap.imaging.background import estimate_background
from mocap.imaging.resample import downscale, working_factor
from mocap.imaging.scene import SceneColours
from mocap.run.setup import choose_background

#: Largest per-pixel error (0-255, any channel) of the estimated background, with noise sigma 2.
BACKGROUND_ERROR_BOUND = 12


@pytest.mark.parametrize("factor", [1, 2, 3, 4])
def test_downscale_is_the_rounded_block_mean(factor):
    frame = np.random.default_rng(factor).integers(0, 256, (50, 70, 3), dtype=np.uint8)
    h, w = 50 // factor, 70 // factor
    reference = downscale_local_mean(frame[:h * factor, :w * factor].astype(float), (factor, factor, 1))
    np.testing.assert_array_equal(downscale(frame, factor), np.floor(reference + 0.5).astype(np.uint8))


def test_working_factor_brings_the_width_nearest_to_the_target():
    assert working_factor(640, 480) == 4          # 160x120
    assert working_factor(768, 432) == 5          # 153 wide: nearer 160 than 192 (k=4)
    assert working_factor(160, 120) == 1
    assert working_factor(100, 80) == 1           # never enlarged
    assert working_factor(1920, 1080, 320) == 6
    with pytest.raises(ValueError, match="working width"):
        working_factor(640, 480, 8)


def _clip(moving: bool, n: int = 24, size=(60, 80), seed=0, texture=150.0):
    """A textured static background and a 20x14 'actor' (a uniform red block with a face-
    coloured top) that walks across it, or stands still, with sensor noise."""
    rng = np.random.default_rng(seed)
    h, w = size
    background = np.clip(120 + ndi.gaussian_filter(rng.normal(0, 1, (h, w, 3)), (3, 3, 0)) * texture, 0, 255)
    frames = []
    for t in range(n):
        frame = background.copy()
        left = int(round(t * (w - 14) / (n - 1))) if moving else 30
        frame[20:40, left:left + 14] = (200, 40, 40)
        frame[14:20, left + 4:left + 10] = (220, 170, 140)
        frames.append(np.clip(np.round(frame + rng.normal(0, 2, frame.shape)), 0, 255).astype(np.uint8))
    return frames, background


def test_estimated_background_recovers_the_static_scene_behind_a_moving_actor():
    frames, truth = _clip(moving=True)
    estimate, free_share = estimate_background(frames)
    assert estimate.shape == truth.shape and estimate.dtype == np.uint8
    error = np.abs(estimate.astype(float) - truth)
    assert error.max() <= BACKGROUND_ERROR_BOUND
    # the plain temporal median would keep the actor where it lingers less than half the time? it
    # does not here; the mask still leaves most frames free at every pixel
    assert free_share.min() > 0.5


def test_auto_choice_uses_the_estimate_when_the_actor_moves():
    frames, truth = _clip(moving=True)
    background, account = choose_background(frames)
    assert account.mode == "auto" and account.used and background is not None
    assert np.abs(background.astype(float) - truth).max() <= BACKGROUND_ERROR_BOUND


def test_auto_choice_is_colour_only_when_the_actor_never_moves():
    frames, _ = _clip(moving=False)
    background, account = choose_background(frames)
    assert background is None and account.mode == "auto" and not account.used
    assert account.details["evidence"]["frames_with_person"] == 0.0


def test_scene_colours_leave_the_scene_out_and_keep_the_person():
    frames, _ = _clip(moving=False, texture=40.0)           # a plain wall
    frame = frames[0]
    box = (12, 28, 30, 18)                                  # the actor fills 60 % of it
    scene = SceneColours.learn(frame, box, ratio=1.5)
    mask = scene.foreground(frame)
    assert mask[22:38, 32:42].mean() > 0.95                 # the red block
    outside = np.ones(mask.shape, bool)
    outside[12:42, 28:46] = False
    assert mask[outside].mean() < 0.1                       # the scene outside the box


def test_background_is_found_where_different_people_stand_most_of_the_time():
    # one spot: three people in turn (25 %, 25 %, 20 % of the frames), empty the other 30 %; a
    # median gives a person there, the most frequent colour is the empty scene's
    frames, truth = _clip(moving=False, n=20)
    rng = np.random.default_rng(5)
    colours = [(200, 40, 40)] * 5 + [(40, 60, 200)] * 5 + [(40, 160, 40)] * 4 + [None] * 6
    clip = []
    for frame, colour in zip(frames, colours):
        frame = frame.copy()
        region = truth[14:40, 30:44] if colour is None else np.array(colour, float)
        frame[14:40, 30:44] = np.clip(np.round(region + rng.normal(0, 2, (26, 14, 3))), 0, 255)
        clip.append(frame)
    median = np.median(np.stack(clip), axis=0)
    assert np.abs(median[20:34, 32:42] - truth[20:34, 32:42]).max() > 20     # the median is not the scene there
    estimate, _ = estimate_background(clip)
    assert np.abs(estimate.astype(float) - truth).max() <= BACKGROUND_ERROR_BOUND
