"""Hair and lower-body colour classes: the face/hair split of the head, F telling the front of the
body from its back, the colour model learning hair, and merging a class the image lacks."""
from dataclasses import replace

import numpy as np
import pytest

from mocap.body import PARAMETER_INDEX as P, BodyDimensions, BodyModel, neutral_pose
from mocap.body.dimensions import PART_NAMES, PartSize
from mocap.body.mesh import HAIR_NAPE_DROP
from mocap.body.skeleton import MESH_PART_NAMES
from mocap.calibrate import Calibration, colour_model_from_pose
from mocap.cost import RegionCost
from mocap.imaging import prepare_frame, rgb_to_hsv
from mocap.labels import PAPER_CLASS_NAMES
from mocap.render import Camera, render
from mocap.synth.actor import Actor
from mocap.synth.sensor import linear_to_srgb
from mocap.synth.shading import Light, render_actor

CAMERA = Camera.default(160, 120)
HEAD, HAIR = MESH_PART_NAMES.index("head") + 1, MESH_PART_NAMES.index("hair") + 1
#: Known hair colour (sRGB): very dark brown (achromatic to the colour model: chroma < 0.06).
HAIR_SRGB = (0.12, 0.09, 0.07)
BACKGROUND_SRGB = (0.55, 0.6, 0.55)


def segment_area_share(h: float) -> float:
    """Share of a disc's area above the chord at height h (radius 1): (acos h - h sqrt(1 - h²)) / pi."""
    return (np.arccos(h) - h * np.sqrt(1.0 - h * h)) / np.pi


def head_pose(yaw: float) -> np.ndarray:
    """The head centred in the image, 0.9 m away (near-orthographic for the bound), chest turned by ``yaw``."""
    dims = BodyDimensions()
    q = neutral_pose()
    q[P["root_z"]] = 0.9
    head_centre = dims["torso"].length + 0.7 * dims["neck"].length + 0.5 * dims["head"].length
    q[P["root_y"]] = head_centre
    q[P["chest_yaw"]] = yaw
    return q


@pytest.mark.parametrize("yaw, what", [(0.0, "face"), (np.pi, "hair")])
def test_head_from_the_front_is_mostly_face_and_from_behind_mostly_hair(yaw, what):
    # An ellipsoid seen along its depth axis projects to an ellipse; the hair visible from the
    # front is the crown above the hairline h (in half head lengths), from behind the back of the
    # head above h - HAIR_NAPE_DROP: the shares of the disc above those chords.
    h = BodyDimensions().hairline
    hair_front = segment_area_share(h)                       # 0.22
    hair_back = segment_area_share(h - HAIR_NAPE_DROP)       # 0.72
    parts = render(head_pose(yaw), BodyModel.build(resolution=24), CAMERA).parts
    face, hair = np.count_nonzero(parts == HEAD), np.count_nonzero(parts == HAIR)
    assert face + hair > 400                                 # a big head, so the shares mean something
    share = hair / (face + hair)
    if what == "face":
        assert share == pytest.approx(hair_front, abs=0.06)
        assert 1 - share > 0.7
    else:
        assert share == pytest.approx(hair_back, abs=0.06)
        assert share > 0.65


def test_paper_model_has_no_hair_and_no_lower_body():
    paper = BodyModel.build(BodyDimensions().without_extensions(), resolution=8)
    assert paper.class_names == PAPER_CLASS_NAMES
    assert set(np.unique(paper.mesh.triangle_part)) == set(range(len(PART_NAMES)))
    full = BodyModel.build(resolution=8)
    assert full.class_names == ("skin", "clothes", "hair", "lower_body")
    assert full.mesh.n_triangles == paper.mesh.n_triangles + 24     # the lower body; the hair cut adds none


# ----------------------------------------------------------------------------- synthetic actor frames
def actor(seed: int = 3, *, bald: bool = False) -> Actor:
    a = Actor.random(np.random.default_rng(seed), pattern="plain")
    hair = a.appearance.skin if bald else HAIR_SRGB
    return replace(a, appearance=replace(a.appearance, hair=hair))


def actor_pose(yaw: float) -> np.ndarray:
    q = neutral_pose()
    q[P["root_z"]] = 2.0
    q[P["chest_yaw"]] = yaw
    for side in "rl":
        q[P[f"{side}_shoulder_abd"]] = np.radians(25)
    return q


def frame_of(a: Actor, pose: np.ndarray, camera: Camera = CAMERA) -> tuple[np.ndarray, np.ndarray]:
    """sRGB uint8 frame of the actor over a plain background, and that background."""
    from mocap.synth.actor import srgb_to_linear
    background = np.broadcast_to(srgb_to_linear(BACKGROUND_SRGB), (camera.height, camera.width, 3)).copy()
    image, _ = render_actor(a, pose, camera, Light(), background)
    to8 = lambda x: np.round(255 * linear_to_srgb(np.clip(x, 0, 1))).astype(np.uint8)
    return to8(image), to8(background)


def test_colour_model_learns_a_known_hair_colour():
    a = actor()
    calib_pose = actor_pose(np.radians(-60))                  # three-quarter view: face and hair
    calib_pose[P["root_z"]] = 1.5
    frame, background = frame_of(a, calib_pose)
    model = BodyModel.build(a.dims, resolution=12)
    colour = colour_model_from_pose(frame, background, model, CAMERA, calib_pose)
    assert colour.names == ("skin", "clothes", "hair", "lower_body")
    known = rgb_to_hsv(np.array([[HAIR_SRGB]]))[0, 0]
    mean, cov = colour.means[colour.names.index("hair")], colour.covariances[colour.names.index("hair")]
    # lighting scales linear RGB (key 0.8 + fill + ambient: at most ~1.2, dimmer away from the
    # key), so the value is at most ~1.1 times the albedo's in sRGB (plus a few boundary pixels mixed
    # with skin), and the hue is ignored
    assert 0.3 * known[2] < mean[2] < 1.5 * known[2]
    assert cov[0, 0] > 100.0 ** 2                            # achromatic: uniform hue
    skin = colour.means[colour.names.index("skin")]
    assert skin[2] - mean[2] > 0.2                           # told apart from the skin
    # the actor's hair pixels (its shading's hairline) are labelled hair
    labels = prepare_frame(frame, background, colour).labels
    hair_model = render(calib_pose, model, CAMERA).parts == HAIR
    assert np.mean(labels[hair_model] == colour.names.index("hair") + 1) > 0.6


def test_region_cost_with_hair_tells_the_back_from_its_mirror():
    # turning: facing away at -105 degrees; its front/back mirror (reflected in depth) faces the
    # camera at -75. Far away through a long lens (near-orthographic) the two silhouettes of a
    # front/back-symmetric body coincide, so only the colours inside can tell them apart.
    camera = Camera.default(160, 120, hfov_deg=8.0)

    def pose(yaw_deg, depth):
        q = neutral_pose()
        q[P["root_z"]], q[P["chest_yaw"]] = depth, np.radians(yaw_deg)
        return q

    a = actor()
    truth, mirror = pose(-105, 14.0), pose(-75, 14.0)
    calib = pose(-60, 11.0)                                  # calibration: face and hair in view
    calib_frame, background = frame_of(a, calib, camera)
    frame, _ = frame_of(a, truth, camera)

    def costs(dims, class_names):
        model = Calibration(dims, calib, camera, class_names).body_model(12)
        colour = colour_model_from_pose(calib_frame, background, model, camera, calib)
        model = model.with_class_names(colour.names)
        labels = prepare_frame(frame, background, colour).labels
        cost = RegionCost(labels, model, camera)
        return colour.names, cost(truth), cost(mirror)

    names, paper_truth, paper_mirror = costs(a.dims.without_extensions(), PAPER_CLASS_NAMES)
    assert names == PAPER_CLASS_NAMES
    full_names, full_truth, full_mirror = costs(a.dims, ("skin", "clothes", "hair", "lower_body"))
    assert full_names == ("skin", "clothes", "hair", "lower_body")
    # the paper's two classes cannot tell them apart (within 5 %; here the mirror even wins) ...
    assert abs(paper_mirror - paper_truth) < 0.05 * paper_truth
    # ... with hair and lower body the truth is clearly better
    assert full_truth < 0.8 * full_mirror


def test_bald_actor_gives_the_two_class_region_cost():
    a = actor(bald=True)
    dims = BodyDimensions({n: s for n, s in a.dims.parts.items() if n in PART_NAMES}, a.dims.hairline)
    calib = actor_pose(np.radians(-150))
    frame, background = frame_of(a, calib)
    model = BodyModel.build(dims, resolution=12)
    colour = colour_model_from_pose(frame, background, model, CAMERA, calib)
    assert colour.names == PAPER_CLASS_NAMES                 # no hair in the image: merged into skin
    merged = model.with_class_names(colour.names)
    assert merged.part_label[MESH_PART_NAMES.index("hair")] == merged.part_label[MESH_PART_NAMES.index("head")]
    two_class = BodyModel.build(dims.without_extensions(), resolution=12)
    labels = prepare_frame(frame, background, colour).labels
    assert not np.isin(labels, [3, 4]).any()
    rng = np.random.default_rng(0)
    for yaw in rng.uniform(-np.pi, np.pi, 5):
        q = actor_pose(yaw)
        f_merged, f_two = RegionCost(labels, merged, CAMERA)(q), RegionCost(labels, two_class, CAMERA)(q)
        # the same classes on the same image; only the head's tessellation differs (two rings
        # moved to the hairline), by a pixel or two of outline
        assert f_merged == pytest.approx(f_two, abs=0.01)


def test_lower_body_trousers_like_the_shirt_merge_into_clothes():
    a = actor()
    app = a.appearance                                       # plain clothes of one colour, trousers alike
    a = replace(a, appearance=replace(app, trousers=app.clothes, clothes_secondary=app.clothes))
    calib = actor_pose(0.0)
    frame, background = frame_of(a, calib)
    colour = colour_model_from_pose(frame, background, BodyModel.build(a.dims, resolution=12), CAMERA, calib)
    assert "lower_body" not in colour.names and "clothes" in colour.names


def test_dimensions_without_extensions_round_trip_as_the_paper_model(tmp_path):
    dims = BodyDimensions().replace("lower_body", length=0.4).with_hairline(0.3)
    assert BodyDimensions.from_dict(dims.to_dict()) == dims
    old = dims.without_extensions().to_dict()
    assert "hairline" not in old and "lower_body" not in old["parts"]
    assert BodyDimensions.from_dict(old) == dims.without_extensions()
    with pytest.raises(ValueError, match="hairline"):
        dims.with_hairline(1.5)
    assert BodyDimensions().scaled(2.0).hairline == BodyDimensions().hairline
    assert BodyDimensions().scaled(2.0)["lower_body"] == PartSize(0.6, 0.64, 0.46)


@pytest.mark.slow
def test_auto_calibration_sets_the_lower_body_and_the_hairline():
    from mocap.calibrate import auto_calibrate
    a = actor()
    pose = actor_pose(0.0)
    pose[P["root_z"]] = 1.5
    frame, background = frame_of(a, pose)
    cal = auto_calibrate(frame, background, CAMERA)
    base = BodyDimensions()
    assert "lower_body" in cal.class_names and cal.dims.has("lower_body")
    # the lower body follows the fitted torso width
    ratio = lambda d: d["lower_body"].width / d["torso"].width
    assert ratio(cal.dims) == pytest.approx(ratio(base))
    assert cal.dims.hairline is not None
    if "hair" in cal.class_names:                            # fitted only when the frame supports hair
        assert 0.0 <= cal.dims.hairline <= 0.9
    else:
        assert cal.dims.hairline == base.hairline
    model = cal.body_model(8)
    assert model.class_names == cal.class_names
    assert np.linalg.norm(model.joint_positions(cal.initial_pose) - BodyModel.build(a.dims).joint_positions(pose),
                          axis=1).mean() < 0.08


def test_calibration_file_from_before_the_classes_loads_as_the_paper_model():
    from mocap.body.skeleton import DEFAULT_PART_CLASS
    old = Calibration(BodyDimensions().without_extensions(), class_names=PAPER_CLASS_NAMES).to_dict()
    old["part_class"] = {p: DEFAULT_PART_CLASS[p] for p in PART_NAMES}          # the nine parts of old files
    model = Calibration.from_dict(old).body_model(8)
    paper = BodyModel.build(BodyDimensions().without_extensions(), resolution=8)
    assert model.class_names == PAPER_CLASS_NAMES
    np.testing.assert_array_equal(model.mesh.triangle_part, paper.mesh.triangle_part)
    np.testing.assert_array_equal(model.part_label[:len(PART_NAMES)], paper.part_label[:len(PART_NAMES)])
    # the default calibration has every class and round-trips
    full = Calibration()
    assert Calibration.from_dict(full.to_dict()).body_model(8).class_names == ("skin", "clothes", "hair", "lower_body")
