"""The actor drawn with hair all round the head (``face=False``, issue 49): no face skin and no
features on the head's pixels, everything else as with the face."""
from dataclasses import replace

import numpy as np
import pytest

from mocap.body.dimensions import PART_NAMES
from mocap.body.pose import HEADING, PARAMETER_INDEX
from mocap.body.skeleton import HEAD_NECK_OVERLAP
from mocap.synth import sequence_poses, setup_sequence
from mocap.synth.actor import srgb_to_linear
from mocap.synth.shading import _albedo, render_actor

HEAD = PART_NAMES.index("head")


def _head_render(face: bool):
    """The head's pixels (K, 3) and the actor's hair and skin colours (linear), facing the camera."""
    setup = setup_sequence("gestures-1", seed=3, size=(320, 240), face=face)
    # hair and skin of unlike hue, so that a pixel's chromaticity says which it is
    appearance = replace(setup.actor.appearance, skin=(0.85, 0.62, 0.5), hair=(0.2, 0.25, 0.6))
    actor = replace(setup.actor, appearance=appearance)
    pose = sequence_poses(setup, frames=1)[0][0].copy()
    pose[PARAMETER_INDEX[HEADING]] = 0.0
    image, parts = render_actor(actor, pose, setup.render_camera, setup.light, setup.background)
    return image[parts == HEAD], srgb_to_linear(appearance.hair), srgb_to_linear(appearance.skin)


def _off_colour(pixels, colour):
    """Per pixel, how far its colour lies from a mix of ``colour`` and white (a shade of it plus
    the key light's white highlight): the norm of its unit RGB direction outside that plane."""
    basis, _ = np.linalg.qr(np.stack([colour, np.ones(3)], axis=1))
    unit = pixels / np.linalg.norm(pixels, axis=1, keepdims=True)
    return np.linalg.norm(unit - unit @ basis @ basis.T, axis=1)


@pytest.mark.parametrize("face", [True, False])
def test_hair_all_round_leaves_no_face_on_the_head(face):
    pixels, hair, skin = _head_render(face)
    assert len(pixels) > 500
    near_hair = _off_colour(pixels, hair) < 0.02
    near_skin = _off_colour(pixels, skin) < 0.02
    if face:
        assert near_skin.mean() > 0.3                  # the face's skin is seen
        assert near_hair.mean() > 0.1                  # and the hair above it
    else:
        assert near_hair.all()                         # hair colour on every pixel: no skin, no eyes, no mouth
        assert not near_skin.any()


@pytest.mark.parametrize("face", [True, False])
def test_hair_all_round_has_no_eyes_or_mouth(face):
    """The albedo at the eyes, the mouth and the cheek (head frame: up -y, the face towards -z)."""
    setup = setup_sequence("gestures-1", seed=3, face=face)
    actor, dims = setup.actor, setup.actor.dims
    start = (1.0 - HEAD_NECK_OVERLAP) * dims["neck"].length
    half_l, half_w, half_d = 0.5 * dims["head"].length, 0.5 * dims["head"].width, 0.5 * dims["head"].depth
    # (x, v) in the head's units (x across, v from -1 chin to +1 crown): eyes, mouth, cheek
    spots = [(-0.38, 0.08), (0.38, 0.08), (0.0, -0.5), (0.6, -0.2)]
    local = np.array([[x * half_w, -(start + half_l + v * half_l), -0.95 * half_d] for x, v in spots])
    albedo, _ = _albedo(actor, np.full(len(spots), HEAD), local, np.zeros(len(spots)))
    hair, skin = srgb_to_linear(actor.appearance.hair), srgb_to_linear(actor.appearance.skin)
    if face:
        assert np.all(albedo[:2].sum(axis=1) < 0.5 * skin.sum())     # dark eyes
        assert not np.allclose(albedo[2], skin)                       # a mouth
        assert np.allclose(albedo[3], skin)                           # skin on the cheek
    else:
        assert np.allclose(albedo, hair)                              # hair, nothing else


def test_faceless_figure_differs_only_on_the_head():
    with_face = setup_sequence("turning", seed=1, size=(160, 120))
    without = setup_sequence("turning", seed=1, size=(160, 120), face=False)
    assert without.actor.appearance.face is False and with_face.actor.appearance.face is True
    assert without.actor.appearance.to_dict()["face"] is False
    assert "face" not in with_face.actor.appearance.to_dict()          # old meta.json files unchanged
    pose = sequence_poses(with_face, frames=1)[0][0]
    a, _ = with_face.radiance(pose)
    b, _ = without.radiance(pose)
    _, parts = render_actor(with_face.actor, pose, with_face.camera, with_face.light,
                            with_face.background_radiance)
    differs = np.any(np.abs(a - b) > 1e-9, axis=2)
    assert differs.any()
    rows, cols = np.nonzero(parts == HEAD)
    box = np.zeros_like(differs)
    box[max(rows.min() - 2, 0):rows.max() + 3, max(cols.min() - 2, 0):cols.max() + 3] = True
    assert not (differs & ~box).any()                 # the body, clothes and background are the same
