"""Articulated upper-body model: pose vector, joint limits, dimensions, kinematics, mesh."""
from mocap.body.dimensions import DEFAULT_PART_SIZES, PART_NAMES, BodyDimensions, PartSize
from mocap.body.kinematics import Skeleton, joint_positions, segment_transforms
from mocap.body.mesh import BodyMesh, build_mesh, resolution_for_image
from mocap.body.model import BodyModel
from mocap.body.pose import (ANGLE_NAMES, JOINT_LIMITS, N_PARAMETERS, PARAMETER_INDEX, PARAMETER_NAMES,
                             POSITION_NAMES, check_pose, clamp_to_limits, neutral_pose, pose_from_dict,
                             pose_to_dict, within_limits)
from mocap.body.skeleton import DEFAULT_PART_CLASS, JOINT_INDEX, JOINT_NAMES, PART_SEGMENT, SEGMENT_NAMES

__all__ = [
    "ANGLE_NAMES", "BodyDimensions", "BodyMesh", "BodyModel", "DEFAULT_PART_CLASS", "DEFAULT_PART_SIZES",
    "JOINT_INDEX", "JOINT_LIMITS", "JOINT_NAMES", "N_PARAMETERS", "PARAMETER_INDEX", "PARAMETER_NAMES", "PART_NAMES",
    "PART_SEGMENT", "POSITION_NAMES", "PartSize", "SEGMENT_NAMES", "Skeleton", "build_mesh", "check_pose",
    "clamp_to_limits", "joint_positions", "neutral_pose", "pose_from_dict", "pose_to_dict",
    "resolution_for_image", "segment_transforms", "within_limits",
]
