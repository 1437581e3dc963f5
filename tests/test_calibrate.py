"""Automatic first-frame calibration recovers a known actor: dimensions and pose of a frame
rendered from them (values, not only that it runs)."""
import numpy as np
import pytest

from mocap.body import PARAMETER_INDEX, BodyDimensions
from mocap.body.model import BodyModel
from mocap.body.pose import neutral_pose
from mocap.calibrate import AutoCalibrationConfig, Calibration, PROPORTION_FACTORS, auto_calibrate
from mocap.render import Camera, render

CAMERA = Camera.default(160, 120)
SKIN_RGB, CLOTHES_RGB, HAIR_RGB, TROUSERS_RGB = (205, 150, 120), (40, 70, 160), (45, 30, 20), (60, 60, 65)


def _scaled(base: BodyDimensions, factors: dict[str, float]) -> BodyDimensions:
    """Body dimensions with each factor of :data:`PROPORTION_FACTORS` applied by hand."""
    parts = dict(base.parts)
    for name, f in factors.items():
        scaled_parts, sizes = PROPORTION_FACTORS[name]
        for p in scaled_parts:
            s = parts[p]
            parts[p] = type(s)(**{k: getattr(s, k) * (f if k in sizes else 1.0) for k in ("length", "width", "depth")})
    return BodyDimensions(parts, base.hairline)


def _actor_scene():
    """A frame of a known actor (own proportions, arms raised 35°, elbows bent 20°, 2.2 m away)
    rendered by our model in flat colours over a noisy background: dims, pose, labels, frame, background."""
    dims = _scaled(BodyDimensions(), {"torso_width": 1.1, "torso_length": 0.95, "arm_length": 0.92,
                                      "arm_width": 1.1, "head_size": 1.05})
    pose = neutral_pose((0.05, 0.3, 2.2))
    for side in ("r", "l"):
        pose[PARAMETER_INDEX[f"{side}_shoulder_abd"]] = np.radians(35.0)
        pose[PARAMETER_INDEX[f"{side}_elbow_flex"]] = np.radians(20.0)
    labels = render(pose, BodyModel.build(dims), CAMERA).labels
    rng = np.random.default_rng(0)
    background = np.clip(rng.normal(0.35, 0.03, (*CAMERA.shape, 3)) + np.linspace(0, 0.2, CAMERA.width)[None, :, None],
                         0, 1)
    background = (background * 255).astype(np.uint8)
    frame = background.copy()
    frame[labels == 1] = SKIN_RGB
    frame[labels == 2] = CLOTHES_RGB
    frame[labels == 3] = HAIR_RGB
    frame[labels == 4] = TROUSERS_RGB
    frame = np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8)
    return dims, pose, labels, frame, background


@pytest.fixture(scope="module")
def actor():
    """The known actor's frame (:func:`_actor_scene`) and the calibration it fits."""
    dims, pose, labels, frame, background = _actor_scene()
    fitted = auto_calibrate(frame, background, CAMERA, config=AutoCalibrationConfig(evaluations=600))
    return dims, pose, labels, fitted


@pytest.mark.slow
def test_keypoints_pull_the_calibrated_joints_onto_them(actor):
    """Given the actor's true 2D joints, the calibration's joints project onto them (shoulder
    width and place, head, arms), at least as well as from the silhouette alone."""
    from mocap.io.keypoints import Keypoints

    dims, pose, _, fitted = actor
    _, _, _, frame, background = _actor_scene()
    true_uv = CAMERA.project(BodyModel.build(dims).joint_positions(pose))
    keypoints = Keypoints(true_uv, np.ones(len(true_uv)))
    with_keypoints = auto_calibrate(frame, background, CAMERA, config=AutoCalibrationConfig(evaluations=600),
                                    keypoints=keypoints)
    miss = lambda c: np.linalg.norm(CAMERA.project(c.body_model().joint_positions(c.initial_pose)) - true_uv, axis=1)
    # on this clean frame the silhouette alone fits well too (measured 0.37 px mean, 0.88 max; with the
    # keypoints 0.33 and 0.69): the keypoints must keep every joint within a pixel and not do worse
    assert miss(with_keypoints).max() < 0.8                       # pixels at 160x120
    assert miss(with_keypoints).mean() <= miss(fitted).mean()


@pytest.mark.slow
def test_keypoints_with_left_and_right_swapped_calibrate_the_same_body(actor):
    """The detector's left and right swapped (as MediaPipe does on a figure whose face it does not
    see): the calibration decides the labelling as the tracker does, and fits the same body and
    pose as from the right labels, to the float (the keypoint distance is the lower of the two
    labellings, computed in the model's joint order)."""
    from mocap.io.keypoints import Keypoints

    dims, pose, _, _ = actor
    _, _, _, frame, background = _actor_scene()
    true_uv = CAMERA.project(BodyModel.build(dims).joint_positions(pose))
    keypoints = Keypoints(true_uv, np.ones(len(true_uv)))
    config = AutoCalibrationConfig(evaluations=300)
    right = auto_calibrate(frame, background, CAMERA, config=config, keypoints=keypoints)
    swapped = auto_calibrate(frame, background, CAMERA, config=config, keypoints=keypoints.swapped())
    np.testing.assert_array_equal(swapped.initial_pose, right.initial_pose)
    assert swapped.dims.to_dict() == right.dims.to_dict()
    # and it is the right body: each arm's joints on their own keypoints
    joints_uv = CAMERA.project(swapped.body_model().joint_positions(swapped.initial_pose))
    assert np.linalg.norm(joints_uv - true_uv, axis=1).max() < 1.5


@pytest.mark.slow
def test_auto_calibrate_recovers_position_depth_and_arm_pose(actor):
    _, pose, _, fitted = actor
    assert isinstance(fitted, Calibration) and fitted.camera == CAMERA
    q = fitted.initial_pose
    x, y, z = (PARAMETER_INDEX[n] for n in ("root_x", "root_y", "root_z"))
    # bounds: 8 cm across the image, 15 cm (7 %) in depth, whose scale one view leaves to the proportions;
    # elbows within 15 degrees (12.5 measured with the four-class model, 7.5 with two)
    assert abs(q[x] - pose[x]) < 0.08 and abs(q[y] - pose[y]) < 0.08
    assert abs(q[z] - pose[z]) < 0.15
    for side in ("r", "l"):
        for joint, bound_deg in (("shoulder_abd", 8.0), ("elbow_flex", 15.0)):
            i = PARAMETER_INDEX[f"{side}_{joint}"]
            assert abs(np.degrees(q[i] - pose[i])) < bound_deg, (side, joint, np.degrees(q[i]))
    assert abs(np.degrees(q[PARAMETER_INDEX["chest_yaw"]])) < 5.0


@pytest.mark.slow
def test_auto_calibrate_recovers_dimensions_and_silhouette(actor):
    dims, _, labels, fitted = actor
    for part in ("r_upper_arm", "r_forearm", "l_upper_arm", "l_forearm"):
        # within 5 % of the true arm lengths (the default adult it starts from is 8 % off; measured: 2 %).
        # The torso's length is not asserted: from one view it trades with depth (measured: +9 %).
        assert abs(fitted.dims[part].length / dims[part].length - 1.0) < 0.05, part
        assert abs(BodyDimensions()[part].length / dims[part].length - 1.0) > 0.05
    got = render(fitted.initial_pose, fitted.body_model(), CAMERA).labels > 0
    truth = labels > 0
    assert np.count_nonzero(got & truth) / np.count_nonzero(got | truth) > 0.85


def test_the_calibration_reads_the_detectors_labels_where_it_shows_the_front():
    """Issue 49 item 5: where the detector shows the front (its left shoulder on the image's right),
    the calibration's keypoint distance is its own labelling's, even where the swapped reading
    would be lower; elsewhere it is the lower of the two. References: ``KeypointCost`` with
    ``swap`` off and on."""
    from mocap.body.skeleton import JOINT_NAMES
    from mocap.calibrate import calibration_keypoint_cost
    from mocap.cost import KeypointCost
    from mocap.io.keypoints import Keypoints

    model = BodyModel.build(BodyDimensions())
    pose = neutral_pose()
    pose[PARAMETER_INDEX["r_shoulder_abd"]] = np.radians(60.0)      # the arms apart, unlike
    uv = CAMERA.project(model.joint_positions(pose))
    index = {name: i for i, name in enumerate(JOINT_NAMES)}
    # the shoulders 1 px apart, the front shown; every other arm keypoint on the other arm's joint
    labelled = uv.copy()
    centre = 0.5 * (uv[index["l_shoulder"]] + uv[index["r_shoulder"]])
    labelled[index["l_shoulder"]], labelled[index["r_shoulder"]] = centre + (0.5, 0.0), centre - (0.5, 0.0)
    for joint in ("elbow", "wrist", "hand"):
        labelled[index[f"l_{joint}"]], labelled[index[f"r_{joint}"]] = uv[index[f"r_{joint}"]], uv[index[f"l_{joint}"]]
    mirrored = labelled * (-1.0, 1.0) + (CAMERA.width, 0.0)          # the same seen from behind: no front
    foreground = np.ones((CAMERA.height, CAMERA.width), bool)
    values = {}
    for points, front in ((labelled, True), (mirrored, False)):
        keypoints = Keypoints(points, np.ones(len(points)))
        assert keypoints.shows_front() is front
        own, either = (KeypointCost(points, np.ones(len(points)), model, CAMERA, foreground=foreground, swap=s)(pose)
                       for s in (False, True))
        values[front] = own, either, calibration_keypoint_cost(keypoints, model, CAMERA, foreground)(pose)
    own, either, got = values[True]
    assert either < own and got == own           # the swapped reading is lower, and not taken
    own, either, got = values[False]
    assert got == either


def test_proportion_factors_scale_each_size_in_the_tables_order():
    """The calibration's trial body (``_apply_factors``) against the factors applied one by one,
    a new PartSize each time, with and without the optional lower body."""
    from mocap.body import PartSize
    from mocap.calibrate import _apply_factors

    rng = np.random.default_rng(8)
    for base in (BodyDimensions(), BodyDimensions().without_extensions()):
        for _ in range(20):
            factors = rng.uniform(0.75, 1.35, len(PROPORTION_FACTORS))
            parts = dict(base.parts)
            for f, (names, axes) in zip(factors, PROPORTION_FACTORS.values()):
                for p in names:
                    if p in parts:
                        s = parts[p]
                        parts[p] = PartSize(*(getattr(s, k) * (f if k in axes else 1.0)
                                              for k in ("length", "width", "depth")))
            assert _apply_factors(base, factors) == BodyDimensions(parts, base.hairline)
