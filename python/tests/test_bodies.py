"""The hapto module's dynamic bodies against the `hapto` command: a stepped session with no
device against `hapto run --stepped --no-devices --record` (the same bodies.trace, byte for byte,
the same poses, the same report), read_trace of a bodies.trace against `hapto trace export`,
the built-in physical grasp scenes against `hapto demo grasp --shape`, experiment_grasp against
`hapto experiment grasp --quick`, and the errors."""

import json
import os
import threading
import time

import numpy
import pytest

import hapto
from conftest import as_numbers

POSE_COLUMNS = {"x": ("center_of_mass", 0), "y": ("center_of_mass", 1),
                "z": ("center_of_mass", 2), "qw": ("rotation", 0), "qx": ("rotation", 1),
                "qy": ("rotation", 2), "qz": ("rotation", 3), "vx": ("velocity", 0),
                "vy": ("velocity", 1), "vz": ("velocity", 2), "wx": ("angular_velocity", 0),
                "wy": ("angular_velocity", 1), "wz": ("angular_velocity", 2)}


@pytest.fixture(scope="module")
def box_scene_file(source_dir):
    return os.path.join(source_dir, "scenes", "examples", "dynamic_box_on_floor.json")


@pytest.fixture(scope="module")
def cli_drop(cli, box_scene_file, tmp_path_factory):
    """`hapto run --stepped --no-devices` on the box scene for 0.5 s: its folder and report."""
    folder = tmp_path_factory.mktemp("cli-drop")
    cli.run("run", "--scene", box_scene_file, "--no-devices", "--stepped", "--duration", 0.5,
            "--quiet", "--record", folder / "rec", "--report", folder / "report.json")
    with open(folder / "report.json") as f:
        return folder / "rec", json.load(f)


def compare_with_export(cli, trace):
    got = hapto.read_trace(trace)
    expected = cli.csv("trace", "export", trace)
    assert list(got) == list(expected)
    for name, values in got.items():
        numpy.testing.assert_array_equal(values, as_numbers(expected[name], values), err_msg=name)
    return got


def test_read_trace_of_a_bodies_trace_gives_trace_export_columns(cli, cli_drop):
    trace = cli_drop[0] / "bodies.trace"
    got = compare_with_export(cli, trace)
    assert list(got) == ["time_s", "id", "x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy",
                         "vz", "wx", "wy", "wz"]
    assert len(got["time_s"]) == 501  # step 0 (the scene's pose) and 500 steps of 1 ms
    header = hapto.trace_header(trace)
    assert header == {"kind": "bodies", "rate_hz": 1000.0, "ids": [1], "samples": 501}


def test_stepped_session_without_devices_matches_hapto_run_no_devices(cli, cli_drop, tmp_path,
                                                                      box_scene_file):
    folder, expected_report = cli_drop
    scene = hapto.load_scene(box_scene_file)  # a version-3 scene file
    with hapto.Session(scene, devices=[], stepped=True, record=tmp_path / "py") as session:
        assert session.run(0.5) == "finished"
        poses = session.bodies()
        live = session.report()
    # The same trace, byte for byte (step mode: the same run every time).
    with open(folder / "bodies.trace", "rb") as a, open(tmp_path / "py" / "bodies.trace",
                                                         "rb") as b:
        assert a.read() == b.read()
    # The poses read from the runtime are the trace's last step.
    last = hapto.read_trace(folder / "bodies.trace")
    assert list(poses["id"]) == [1]
    for name, (column, k) in POSE_COLUMNS.items():
        assert poses[column][0, k] == last[name][-1], name
    assert poses["time_s"][0] == last["time_s"][-1] == 0.5
    assert poses["step"][0] == 500
    numpy.testing.assert_array_equal(poses["center"], poses["center_of_mass"])  # a centred box
    assert poses["rotation"].shape == (1, 4) and poses["sleeping"].dtype == bool
    # report(): the --report JSON, its dynamics part included.
    assert live["dynamics"] == expected_report["dynamics"]
    assert live["devices"] == expected_report["devices"] == []
    assert live["dynamics"]["steps"] == 500 and live["dynamics"]["bodies"][0]["id"] == 1


def test_step_without_devices_counts_dynamics_steps(box_scene_file):
    with hapto.Session(hapto.load_scene(box_scene_file), devices=[], stepped=True) as session:
        session.step(40)
        first = session.bodies()
        session.step(60)
        second = session.bodies()
    assert first["step"][0] == 40 and first["time_s"][0] == pytest.approx(0.04)
    assert second["step"][0] == 100 and second["time_s"][0] == pytest.approx(0.1)
    assert session.time_s == pytest.approx(0.1)


@pytest.mark.parametrize("shape", ["box", "sphere", "mesh"])
def test_dynamic_grasp_scene_is_hapto_demo_grasps_scene(cli, tmp_path, shape):
    cli.run("demo", "grasp", "--shape", shape, "--stepped", "--record",
            tmp_path / "cli")
    expected = hapto.read_trace(tmp_path / "cli" / "bodies.trace")
    scene = hapto.dynamic_grasp_scene(shape)
    assert list(scene.ids) == list(range(8))
    with hapto.Session(scene, devices=[], stepped=True, record=tmp_path / "py") as session:
        session.step(1)
        poses = session.bodies()
    got = hapto.read_trace(tmp_path / "py" / "bodies.trace")
    assert list(poses["id"]) == [0]
    # Step 0 is the scene's own pose: the same object, where the demo's scene has it.
    for name in got:
        assert got[name][0] == expected[name][0], name
    assert numpy.linalg.norm(poses["rotation"][0]) == pytest.approx(1.0)


def test_stepped_sessions_with_hands_and_a_body_repeat_exactly():
    runs = []
    for _ in range(2):
        with hapto.Session(hapto.dynamic_grasp_scene("box"), stepped=True) as session:
            session.step(300)
            runs.append(session.bodies())
            report = session.report()
    for name in runs[0]:
        numpy.testing.assert_array_equal(runs[0][name], runs[1][name], err_msg=name)
    assert [d["ticks"] for d in report["devices"]] == [300, 300]
    assert report["dynamics"]["steps"] == 300


def test_the_gil_is_released_while_a_session_runs(box_scene_file):
    session = hapto.Session(hapto.load_scene(box_scene_file), devices=[], stepped=True)
    session.step(1)
    worker = threading.Thread(target=session.run, args=(5.0,))
    seen = []
    worker.start()
    while worker.is_alive():  # Python code runs here only while run() has the GIL released
        seen.append(int(session.bodies()["step"][0]))
        # Give the GIL back at once: run() takes it for a moment once per control step (to look
        # for a signal), and a poller that kept it would make each step wait for Python's switch
        # interval (5 ms): 5000 steps would take 25 s instead of a fraction of one.
        time.sleep(0.0002)
    worker.join()
    final = int(session.bodies()["step"][0])
    session.stop()
    assert final == 5001
    assert any(1 < s < final for s in seen), "no step seen while run() was running"


def test_body_errors_are_input_errors_with_the_commands_message(cli, tmp_path, box_scene_file):
    with open(box_scene_file) as f:
        scene = json.load(f)
    scene["objects"][-1]["mass_kg"] = -1
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(scene))
    r = cli.run("run", "--scene", bad, "--no-devices", "--stepped", "--duration", 0.1,
                check=False)
    assert r.returncode == 2
    with pytest.raises(hapto.InputError) as e:
        hapto.load_scene(bad)
    assert r.stderr.strip() == "hapto: " + str(e.value)
    assert "mass_kg" in str(e.value)

    (tmp_path / "cut.trace").write_bytes(b"HAPTOBDY" + b"\1\0\0\0")
    r = cli.run("trace", "export", tmp_path / "cut.trace", check=False)
    assert r.returncode == 2
    with pytest.raises(hapto.InputError) as e:
        hapto.read_trace(tmp_path / "cut.trace")
    assert r.stderr.strip() == "hapto: " + str(e.value)


def test_bad_body_arguments_are_input_errors_naming_them(tmp_path, box_scene_file):
    with pytest.raises(hapto.InputError, match=r"devices=\[\]: the scene has no dynamic body"):
        hapto.Session(hapto.default_scene(), devices=[], stepped=True)
    with pytest.raises(hapto.InputError, match="record .*no dynamic body"):
        hapto.Session(hapto.default_scene(), stepped=True, record=tmp_path / "r")
    with pytest.raises(hapto.InputError, match="bodies: the scene has no dynamic body"):
        with hapto.Session(hapto.default_scene(), stepped=True) as session:
            session.step(1)
            session.bodies()
    with pytest.raises(hapto.InputError, match="bodies: the session has not started"):
        hapto.Session(hapto.load_scene(box_scene_file), devices=[], stepped=True).bodies()
    with pytest.raises(hapto.InputError, match="shape 'cone'"):
        hapto.dynamic_grasp_scene("cone")
    with pytest.raises(hapto.InputError, match="repeats 0"):
        hapto.experiment_grasp(quick=True, repeats=0)
    with pytest.raises(hapto.InputError, match="masses_kg: an empty list"):
        hapto.experiment_grasp(quick=True, masses_kg=[])


# Timings (the dynamics step's CPU time) differ from run to run; every other column is the
# step mode's, the same every run.
TIMING_PREFIX = "step_p"


def test_experiment_grasp_returns_hapto_experiment_grasps_table(cli, tmp_path):
    cli.run("experiment", "grasp", "--quick", "--out", tmp_path / "cli")
    with open(tmp_path / "cli" / "grasp.json") as f:
        rows = json.load(f)["rows"]
    table = hapto.experiment_grasp(tmp_path / "py", quick=True)
    assert list(table) == list(rows[0])
    with open(tmp_path / "py" / "grasp.csv") as f:
        assert f.readline().strip().split(",") == list(table)
    # The default cell once per factor: squeeze (0.3 N and the default), mass, stiffness, rate.
    assert list(table["factor"]) == [r["factor"] for r in rows]
    assert len(rows) == 5
    for name, values in table.items():
        if name.startswith(TIMING_PREFIX):
            continue
        assert list(values) == [r[name] for r in rows], name
    assert list(table["squeeze_n"][:2]) == [0.3, 1.5]
    assert list(table["held"][:2]) == ["dropped", "held"]  # below and above the hold limit
    masses = hapto.experiment_grasp(quick=True, squeezes_n=[1.5], masses_kg=[0.05, 0.3])
    assert list(masses["mass_kg"][masses["factor"] == "mass"]) == [0.05, 0.3]
    assert list(masses["squeeze_n"][masses["factor"] == "squeeze"]) == [1.5]
