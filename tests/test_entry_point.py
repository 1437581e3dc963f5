"""One entry point to track a video: every route — the commands ``track``, ``track-many``,
``demo``, ``bench``, the experiments ``docs``, ``long_run``, ``peers`` and the notebooks — calls
:func:`mocap.run.track` (none calls the CLI's ``main``, none builds a run by hand); its options
are a JSON record; ``Camera.working`` is the one reduction to the working resolution."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

from mocap.run import OwnVideoOptions
from mocap.render import Camera
from mocap.track import TrackerConfig

ROOT = Path(__file__).resolve().parents[1]


class _Called(Exception):
    pass


@pytest.fixture
def recorder(monkeypatch):
    """``mocap.run.track`` replaced by one that records its arguments and stops the caller."""
    import mocap.run

    calls = []

    def record(source, out_dir, options=None, *, progress=True, on_setup=None):
        calls.append((source, Path(out_dir), options))
        raise _Called

    monkeypatch.setattr(mocap.run, "track", record)
    return calls


def test_cli_track_calls_the_library_with_its_options(recorder, tmp_path):
    from mocap.cli import main

    video = tmp_path / "clip.mp4"
    video.touch()
    with pytest.raises(_Called):
        main(["track", str(video), "--out", str(tmp_path / "run"), "--hfov", "70", "--height", "1.6",
              "--max-frames", "5", "--no-overlay", "--iterations", "123", "--start", "2", "--no-background"])
    (source, out, options), = recorder
    assert Path(source) == video and out == tmp_path / "run"
    assert options == OwnVideoOptions(hfov_deg=70.0, height_m=1.6, max_frames=5, overlay=False, start=2,
                                      no_background=True, tracker=TrackerConfig(evaluations=123), keypoints="auto")


@pytest.mark.parametrize("command", [["track", "clip.mp4"], ["track-many", "clip.mp4", "--out", "o"],
                                     ["calibrate", "clip.mp4"], ["demo"], ["segment", "clip.mp4"]])
def test_a_command_line_s_defaults_are_the_options_defaults(command):
    """One builder (``own_video_options``) turns every command's arguments into its options, and
    a command line that sets nothing gives ``OwnVideoOptions()``: the same defaults (keypoints
    ``auto`` in both). Each option it shares with the others is declared once."""
    from mocap.cli import build_parser
    from mocap.commands._common import own_video_options

    assert own_video_options(build_parser().parse_args(command)) == OwnVideoOptions()
    assert OwnVideoOptions().keypoints == "auto"


def test_the_shared_options_are_declared_in_one_place():
    """``--hfov``, ``--height``, ``--work-width``, ``--colour``, ``--start``, ``--max-frames``,
    ``--allow-damaged`` and ``--keypoints`` are spelt in ``mocap/commands/_common.py`` alone."""
    for path in sorted((ROOT / "mocap" / "commands").glob("*.py")):
        if path.name == "_common.py":
            continue
        text = path.read_text()
        for option in ("--hfov", "--height", "--work-width", "--colour", "--start", "--max-frames", "--allow-damaged",
                       "--keypoints"):
            assert f'"{option}"' not in text, f"{path.name} declares {option}"


def test_bench_video_stage_calls_the_library(recorder):
    from mocap.bench import video_rows

    with pytest.raises(_Called):
        video_rows(frames=1)
    (source, out, options), = recorder
    assert str(source).endswith(".mp4") and options.max_frames == 2 and options.background is not None


def test_peers_experiment_calls_the_library(recorder, tmp_path):
    from experiments.peers import _track

    with pytest.raises(_Called):
        _track(tmp_path / "clip.mp4", tmp_path / "run", overlay=False)
    (source, out, options), = recorder
    assert options == OwnVideoOptions(overlay=False, overwrite=True, keypoints="none")


def test_demo_calls_the_library_on_the_bundled_sequence(recorder, tmp_path):
    from mocap.cli import main

    with pytest.raises(_Called):
        main(["demo", "--out", str(tmp_path / "demo"), "--iterations", "50", "--no-overlay"])
    (source, out, options), = recorder
    assert (Path(source) / "frames").is_dir() and out == tmp_path / "demo"
    assert options == OwnVideoOptions(overlay=False, tracker=TrackerConfig(evaluations=50), keypoints="none")


def test_track_many_workers_call_the_library(recorder, tmp_path):
    from mocap.run.many import track_input

    with pytest.raises(_Called):
        track_input(str(tmp_path / "clip.mp4"), str(tmp_path / "out"), OwnVideoOptions(max_frames=3))
    (source, out, options), = recorder
    assert options == OwnVideoOptions(max_frames=3)


#: Every route that tracks a video, and what each must call: the run's entry point, or (frame-level
#: control: pushing frames one at a time, looking at the beam) the tracker's API.
ROUTES = {
    "mocap/commands/track.py": "mocap.run.track", "mocap/run/many.py": "mocap.run.track",
    "mocap/commands/demo.py": "mocap.run.track", "mocap/bench.py": "mocap.run.track",
    "experiments/docs.py": "mocap.run.track", "experiments/long_run.py": "mocap.run.track",
    "experiments/peers.py": "mocap.run.track", "notebooks/walkthrough.py": "mocap.run.track",
    "experiments/units.py": "Tracker", "experiments/ambiguity.py": "Tracker",
    # segment tracks nothing: it shows what the image side sees, with the run's own set-up steps
    "mocap/commands/segment.py": "segment", "mocap/run/segment.py": "find_background",
}
#: Names that build a run by hand (the run floor's own parts): used only inside ``mocap/run/``.
RUN_PARTS = ("track_frames", "RunLoop", "RunParams", "find_setup")


def _called_names(path: Path) -> set[str]:
    """Dotted names of every call in a file (``mocap.run.track(...)`` -> ``mocap.run.track``)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Call):
            parts, f = [], node.func
            while isinstance(f, ast.Attribute):
                parts.append(f.attr)
                f = f.value
            if isinstance(f, ast.Name):
                names.add(".".join([f.id, *reversed(parts)]))
    return names


@pytest.mark.parametrize("route, entry", sorted(ROUTES.items()))
def test_every_route_calls_the_one_entry_point(route, entry):
    assert entry in {n.rpartition(".")[2] if "." not in entry else n for n in _called_names(ROOT / route)}, \
        f"{route} does not call {entry}"


def test_nothing_outside_the_run_floor_builds_a_run_by_hand():
    offenders = []
    for folder in ("mocap", "experiments", "notebooks", "docs"):
        for path in (ROOT / folder).glob("**/*.py"):
            if path.is_relative_to(ROOT / "mocap" / "run") or path.name == "calibrate.py":
                continue     # (the calibrate command uses the set-up alone, to write a calibration)
            used = {n.rpartition(".")[2] for n in _called_names(path)}
            offenders += [f"{path.relative_to(ROOT)}: {name}" for name in RUN_PARTS if name in used]
    assert offenders == []


def test_no_library_or_experiment_module_calls_the_cli():
    offenders = []
    for folder in ("mocap", "experiments"):
        for path in (ROOT / folder).glob("**/*.py"):
            if path.parts[-2] == "commands" or path.name in ("cli.py", "__main__.py"):
                continue
            tree = ast.parse(path.read_text(), str(path))
            for node in ast.walk(tree):
                if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith(("mocap.cli",
                                                                                                 "mocap.commands")):
                    offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert offenders == []


def test_options_round_trip_through_json(tmp_path):
    options = OwnVideoOptions(background_frames=(0, 10), hfov_deg=75.0, max_frames=3, calibration=Path("c.json"),
                              tracker=TrackerConfig(evaluations=200, beam=1))
    assert options.calibration == "c.json"
    options.to_json(tmp_path / "options.json")
    assert OwnVideoOptions.from_json(tmp_path / "options.json") == options
    with pytest.raises(ValueError, match="unknown OwnVideoOptions option"):
        OwnVideoOptions.from_dict({"hfvo_deg": 70})
    with pytest.raises(ValueError, match="one of background"):
        OwnVideoOptions(background="bg.png", no_background=True)
    with pytest.raises(ValueError, match="max_frames"):
        OwnVideoOptions(max_frames=0)


def test_camera_working_reduces_once_with_one_size_check():
    full = Camera(642, 481, 500.0, 510.0, 321.0, 240.5)
    work = full.working(642, 481, 4)
    # hand-computed: floor sizes of the reduced image, intrinsics divided by the factor
    assert (work.width, work.height, work.fx, work.fy, work.cx, work.cy) == (160, 120, 125.0, 127.5, 80.25, 60.125)
    assert work.working(642, 481, 4) is work                 # already at the working size
    assert work.enlarged(4, 642, 481) == Camera(642, 481, 500.0, 510.0, 321.0, 240.5)
    with pytest.raises(ValueError, match="calibrate for this video"):
        Camera(320, 240, 300.0, 300.0, 160.0, 120.0).working(642, 481, 4)


def test_the_keypoints_extra_installs_mediapipe_where_its_wheel_exists_and_its_tests_say_why_not():
    """``mediapipe==0.10.14`` (the last release with its pose model in the wheel) has wheels for
    Python 3.11 and 3.12 only: the extra ``keypoints`` carries that marker, so that the default
    install and ``.[test]`` install on 3.13 too, and the MediaPipe tests skip there with the reason."""
    import tomllib

    from packaging.markers import Marker
    from packaging.requirements import Requirement

    from tests.conftest import MEDIAPIPE_UNINSTALLABLE

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    mediapipe, = (Requirement(r) for r in extras["keypoints"])
    assert mediapipe.name == "mediapipe" and str(mediapipe.specifier) == "==0.10.14"
    for version, installs in (("3.11", True), ("3.12", True), ("3.13", False), ("3.14", False)):
        assert mediapipe.marker.evaluate({"python_version": version}) is installs
    assert (MEDIAPIPE_UNINSTALLABLE is None) is mediapipe.marker.evaluate()
    assert not any("mediapipe" in r for r in project["dependencies"])       # the default install has none
    # the test extra takes the extra and, where the pinned CPU torch is held (3.11), the fitting extra
    assert "mocap[keypoints]" in extras["test"]
    fit, = (Requirement(r) for r in extras["test"] if r.startswith("mocap[fit]"))
    assert fit.marker == Marker("python_version < '3.12'")


def test_hung_after_has_its_default_in_the_parser():
    from mocap.cli import build_parser
    from mocap.run.many import HUNG_AFTER_S

    assert build_parser().parse_args(["track-many", "clip.mp4", "--out", "o"]).hung_after == HUNG_AFTER_S
    assert build_parser().parse_args(["track-many", "clip.mp4", "--out", "o", "--hung-after", "5"]).hung_after == 5.0
