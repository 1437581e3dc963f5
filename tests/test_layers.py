"""Dependencies point one way (docs/design.md section 1): the checker on a planted tree, then on the repository."""
from pathlib import Path

import pytest

from tests.layers import layer, violations

ROOT = Path(__file__).resolve().parents[1]


def _tree(tmp_path, files):
    for name, text in files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return tmp_path


CLEAN = {
    "mocap/__init__.py": "",
    "mocap/_numba.py": "",
    "mocap/body/__init__.py": "",
    "mocap/body/pose.py": "import numpy as np\nfrom mocap._numba import jit\n",
    "mocap/render/__init__.py": "",
    "mocap/render/_raster.py": "",
    "mocap/render/rasterize.py": "from mocap.body.pose import np\nfrom mocap.render import _raster\n",
    "mocap/cost.py": "from mocap.render.rasterize import np\n",
    "mocap/track.py": "import mocap.cost\n",
    "mocap/commands/__init__.py": "from mocap.track import x\n",
    "experiments/run.py": "from mocap.commands import y\n",
}


def test_layers_by_module_name():
    assert [layer(m) for m in ("mocap._numba", "mocap.io.files", "mocap.body.pose", "mocap.io.video",
                               "mocap.render.camera", "mocap.imaging.edges", "mocap.cost", "mocap.optimize",
                               "mocap.track", "mocap.synth.sequence", "mocap.calibrate", "mocap.run.loop",
                               "mocap.bench", "mocap.commands.demo", "experiments.sweep",
                               "numpy")] == [0, 0, 1, 2, 3, 4, 4, 5, 6, 6, 6, 7, 7, 8, 8, -1]


def test_a_clean_tree_passes(tmp_path):
    assert violations(_tree(tmp_path, CLEAN)) == []


@pytest.mark.parametrize("name, text, expect", [
    ("mocap/body/kinematics.py", "from mocap.render.rasterize import render\n", "(body) imports mocap.render.rasterize (render)"),
    ("mocap/synth/datasets.py", "def f():\n    from mocap.commands.synth import parse_size\n", "imports mocap.commands.synth (face)"),
    ("mocap/optimize.py", "import mocap.track\n", "(fit) imports mocap.track (track)"),
    ("mocap/cost.py", "from mocap.render import _raster\n", "private name of mocap.render"),
    ("mocap/track.py", "from mocap.cost import _region_cost\n", "private name of mocap.cost"),
    ("mocap/track.py", "from mocap.render._raster import SUBPIXEL\n", "private name of mocap.render"),
    ("mocap/io/video.py", "from mocap.imaging.resample import downscale\n", "(io) imports mocap.imaging.resample (image)"),
    ("mocap/io/bvh.py", "import mocap.track\n", "(io) imports mocap.track (track)"),
    ("mocap/body/dimensions.py", "from mocap.io.bvh import x\n", "(body) imports mocap.io.bvh (io)"),
    ("mocap/track.py", "from mocap.run.loop import x\n", "(track) imports mocap.run.loop (run)"),
    ("mocap/run/loop.py", "from mocap.commands import y\n", "(run) imports mocap.commands (face)"),
])
def test_a_planted_violation_is_found(tmp_path, name, text, expect):
    found = violations(_tree(tmp_path, {**CLEAN, name: text}))
    assert len(found) == 1 and name in found[0] and expect in found[0], found


def test_the_repository_imports_point_one_way():
    found = violations(ROOT)
    assert found == [], "\n".join(found)
