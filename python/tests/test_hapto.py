"""The hapto module against the `hapto` command: the same columns and the same numbers
(render, query, trace export), the same report fields, the same error messages."""

import json
import os

import numpy
import pytest

import hapto
from conftest import as_numbers


def write_path(path, points):
    with open(path, "w") as f:
        f.write("x,y,z\n")
        for p in points:
            f.write("%r,%r,%r\n" % tuple(float(v) for v in p))


@pytest.fixture(scope="module")
def grid_scene_file(tmp_path_factory, cli):
    path = tmp_path_factory.mktemp("scene") / "grid.json"
    cli.run("scene", "grid", "--per-side", 3, "-o", path)
    return path


def sweep():
    """A line through the 3x3x3 lattice's middle row of cubes, then back: free motion,
    contacts, and a proxy left behind on the surface."""
    t = numpy.linspace(-0.12, 0.12, 240)
    out = numpy.column_stack([t, numpy.full_like(t, 0.004), numpy.full_like(t, -0.003)])
    return numpy.vstack([out, out[::-1]])


def test_version_is_the_commands(cli):
    assert cli.run("--version").stdout.split() == ["hapto", hapto.__version__]


@pytest.mark.parametrize("index", [None, "grid:4", "octree:2:0.005", "built"])
def test_render_gives_hapto_render_columns_and_numbers(cli, tmp_path, grid_scene_file, index):
    points = sweep()
    write_path(tmp_path / "path.csv", points)
    args = ["render", "--scene", grid_scene_file, "--path", tmp_path / "path.csv", "--rate", 2000]
    scene = hapto.load_scene(grid_scene_file)
    given = index
    if index == "built":
        given = hapto.build_index(scene, "grid:4")
        args += ["--index", "grid:4"]
    elif index is not None:
        args += ["--index", index]
    expected = cli.csv(*args)
    got = hapto.render(scene, points, index=given, rate_hz=2000)
    assert list(got) == list(expected)
    for name, values in got.items():
        assert len(values) == len(points)
        numpy.testing.assert_array_equal(values, as_numbers(expected[name], values), err_msg=name)
    assert got["contacts"].max() > 0  # the path touched the cubes: the test compares contacts


def test_query_gives_hapto_query_candidates(cli, tmp_path, grid_scene_file):
    points = sweep()[::20]
    write_path(tmp_path / "points.csv", points)
    expected = cli.csv("query", "--scene", grid_scene_file, "--points", tmp_path / "points.csv",
                       "--index", "grid:4")
    index = hapto.build_index(hapto.load_scene(grid_scene_file), "grid:4")
    assert index.spec == "grid:4"
    got = index.query(points)
    for i, text in zip(expected["point"], expected["candidates"]):
        rows = got["point"] == int(i)
        python = [("%d" % o) if t < 0 else ("%d:%d" % (o, t))
                  for o, t in zip(got["id"][rows], got["triangle"][rows])]
        assert " ".join(python) == text
    assert len(got["id"]) > 0


def compare_with_export(cli, trace):
    got = hapto.read_trace(trace)
    expected = cli.csv("trace", "export", trace)
    assert list(got) == list(expected)
    for name, values in got.items():
        if values.dtype.kind in "US":
            assert list(values) == expected[name]
        else:
            numpy.testing.assert_array_equal(values, as_numbers(expected[name], values),
                                             err_msg=name)
    return got


def test_read_trace_gives_trace_export_columns_version_2(cli, tmp_path):
    cli.run("run", "--duration", 0.3, "--no-realtime", "--quiet", "--record", tmp_path / "runs")
    got = compare_with_export(cli, tmp_path / "runs" / "left.trace")
    assert len(got["tick"]) > 0
    assert "proxy_x_m" in got and "missed_deadline" in got
    assert hapto.trace_header(tmp_path / "runs" / "left.trace")["name"] == "left"


def test_read_trace_gives_trace_export_columns_version_1(cli, source_dir):
    trace = os.path.join(source_dir, "tools/fuzz/corpus/trace_file/three-ticks.trace")
    got = compare_with_export(cli, trace)
    assert len(got) == 12 and "proxy_x_m" not in got
    assert hapto.trace_header(trace)["version"] == 1


def test_stepped_session_reports_the_run_report_fields(cli, tmp_path):
    cli.run("run", "--duration", 0.2, "--no-realtime", "--quiet", "--report",
            tmp_path / "r.json")
    with open(tmp_path / "r.json") as f:
        expected = json.load(f)
    with hapto.Session(hapto.default_scene(), stepped=True) as session:
        assert session.step(500) == "finished"
        live = session.report()
        final = session.stop()
    # The same fields (a note such as realtime_note is written only when there is one).
    assert {"devices", "total"} <= set(final) <= set(expected)
    assert {"name", "ticks"} <= set(final["devices"][0]) <= set(expected["devices"][0])
    assert [d["name"] for d in final["devices"]] == [d["name"] for d in expected["devices"]]
    # 500 ticks of 1 ms each, per device (step mode: exact, the same every run).
    assert [d["ticks"] for d in final["devices"]] == [500, 500]
    assert [d["ticks"] for d in live["devices"]] == [500, 500]
    assert session.time_s == pytest.approx(0.5)


def test_stepped_sessions_repeat_exactly_and_take_device_dicts():
    devices = [{"name": "solo", "kind": "sim", "rate_hz": 1000}]
    reports = []
    for _ in range(2):
        session = hapto.Session(hapto.grasp_scene(), devices=devices, stepped=True)
        session.run(0.25)
        session.step(10)
        reports.append(session.stop())
    assert [d["name"] for d in reports[0]["devices"]] == ["solo"]
    keys = ("ticks", "candidates_mean", "contact_ticks")
    first, second = reports[0]["devices"][0], reports[1]["devices"][0]
    assert {k: first.get(k) for k in keys} == {k: second.get(k) for k in keys}
    assert first["ticks"] == 260


def test_bad_input_raises_input_error_with_the_commands_message(cli, tmp_path):
    write_path(tmp_path / "path.csv", [(0.0, 0.0, 0.0)])
    missing = tmp_path / "missing.json"
    r = cli.run("render", "--scene", missing, "--path", tmp_path / "path.csv", check=False)
    assert r.returncode == 2
    with pytest.raises(hapto.InputError) as e:
        hapto.load_scene(missing)
    assert r.stderr.strip() == "hapto: " + str(e.value)
    assert isinstance(e.value, ValueError)

    (tmp_path / "bad.trace").write_bytes(b"HAPTOTRC" + b"\0" * 20)
    r = cli.run("trace", "export", tmp_path / "bad.trace", check=False)
    assert r.returncode == 2
    with pytest.raises(hapto.InputError) as e:
        hapto.read_trace(tmp_path / "bad.trace")
    assert r.stderr.strip() == "hapto: " + str(e.value)

    r = cli.run("render", "--scene", missing, "--path", tmp_path / "path.csv", "--index",
                "grid:0", check=False)
    with pytest.raises(hapto.InputError) as e:
        hapto.render(hapto.default_scene(), numpy.zeros((1, 3)), index="grid:0")
    assert r.stderr.strip() == "hapto: " + str(e.value)


def test_bad_arguments_are_input_errors_naming_the_argument():
    scene = hapto.default_scene()
    with pytest.raises(hapto.InputError, match=r"points: expected an \(N, 3\) array"):
        hapto.render(scene, numpy.zeros((4, 2)))
    with pytest.raises(hapto.InputError, match=r"points\[1\]: expected three finite"):
        hapto.render(scene, numpy.array([[0, 0, 0], [numpy.nan, 0, 0]]))
    with pytest.raises(hapto.InputError, match="points: no points"):
        hapto.render(scene, numpy.zeros((0, 3)))
    with pytest.raises(hapto.InputError, match="rate_hz"):
        hapto.render(scene, numpy.zeros((1, 3)), rate_hz=10)
    with pytest.raises(hapto.InputError, match="index: built over another scene"):
        hapto.render(scene, numpy.zeros((1, 3)), index=hapto.build_index(hapto.grasp_scene()))
    with pytest.raises(hapto.InputError, match="only a session made with stepped=True"):
        hapto.Session(scene).step(1)
    with pytest.raises(hapto.InputError, match=r"devices\[0\]"):
        hapto.Session(scene, devices=[{"name": "x", "kind": "nonsense"}])
    with pytest.raises(hapto.InputError, match="per-side|per_side|K"):
        hapto.lattice_scene(per_side=0)


def test_generators_match_the_commands_scene_files(cli, tmp_path):
    cli.run("scene", "random", "--count", 50, "--seed", 7, "-o", tmp_path / "r.json")
    from_file = hapto.load_scene(tmp_path / "r.json")
    made = hapto.random_scene(count=50, seed=7)
    assert len(made) == len(from_file) == 50
    numpy.testing.assert_array_equal(made.ids, from_file.ids)
    assert made.bounds == from_file.bounds
    points = numpy.random.default_rng(1).uniform(-0.12, 0.12, size=(300, 3))
    a, b = hapto.render(made, points), hapto.render(from_file, points)
    for name in a:
        numpy.testing.assert_array_equal(a[name], b[name], err_msg=name)


@pytest.mark.realtime
def test_experiment_scaling_returns_its_tables_as_columns(tmp_path):
    tables = hapto.experiment_scaling(tmp_path, max_devices=2, rates_hz=[1000.0],
                                      duration_s=0.05, repeats=1, cursor=False, realtime=False)
    devices = tables["devices"]
    with open(tmp_path / "devices.csv") as f:
        assert f.readline().strip().split(",") == list(devices)
    assert len(next(iter(devices.values()))) == 2  # device counts 1 and 2 at one rate
    per_device = tables["per_device"]
    assert len(next(iter(per_device.values()))) == 3  # 1 + 2 devices
    assert tables["cursor"] == {}
    counted = hapto.experiment_scaling(tmp_path / "counts", counts=[1, 3], rates_hz=[1000.0],
                                       duration_s=0.05, repeats=3, cursor=False, realtime=False)
    cells = counted["devices"]
    assert list(cells["devices"]) == [1, 3]
    for name in ("load_sum", "median_device_p999", "worst_load_p999"):
        assert all(cells[name + "_lo_pct"] <= cells[name + "_pct"])
        assert all(cells[name + "_pct"] <= cells[name + "_hi_pct"])


def test_device_dicts_carry_force_effects_as_the_device_file_does(cli, tmp_path):
    # A free hand with a device file's effects (a constant pull and a plane spring): a stepped
    # Python session reports exactly what `hapto run --stepped` reports for the same file, and
    # the effects reach the device (its safety filter acts on them; without them it never does).
    effects = [{"type": "constant", "force_n": [0, -0.5, 0]},
               {"type": "spring", "anchor": [0, 0.05, 0], "stiffness_n_per_m": 200,
                "normal": [0, 1, 0]}]
    hand = {"name": "left", "kind": "sim", "sim": {"script": "free"}, "effects": effects}
    path = tmp_path / "hands.json"
    path.write_text(json.dumps({"format": "hapto-devices", "version": 1, "devices": [hand]}))
    cli.run("run", "--devices", path, "--stepped", "--duration", 0.3, "--quiet", "--report",
            tmp_path / "r.json")
    with open(tmp_path / "r.json") as f:
        expected = json.load(f)["devices"][0]
    with hapto.Session(hapto.default_scene(), devices=[hand], stepped=True) as session:
        session.run(0.3)
        got = session.stop()["devices"][0]
    assert got == expected
    assert got["safety"]["clamped"] + got["safety"]["rate_limited"] > 0
    plain = dict(hand)
    del plain["effects"]
    with hapto.Session(hapto.default_scene(), devices=[plain], stepped=True) as session:
        session.run(0.3)
        without = session.stop()["devices"][0]
    assert without["safety"]["clamped"] + without["safety"]["rate_limited"] == 0
