"""mocap: real-time markerless monocular 3D upper-body motion capture on the CPU.

The data flows one way: :mod:`mocap.body` (pose vector, kinematics, mesh) →
:mod:`mocap.render` (camera, Numba rasterizer) → :mod:`mocap.cost` (non-overlapping ratio,
mean edge distance) → :mod:`mocap.optimize` (bounded downhill simplex) → :mod:`mocap.track`
(two-step registration per frame). :mod:`mocap.imaging` turns video frames into the targets
the costs compare against.
"""
__version__ = "0.1.0"
