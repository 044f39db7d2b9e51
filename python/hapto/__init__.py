"""hapto from Python: scenes, indices, the haptic tick along a path, sessions, traces and the
experiments of the multi-device haptic runtime (https://... the `hapto` command's library).

Every table comes back as a dict of numpy arrays, one per column, with the names and numbers of
the matching command's CSV (`pandas.DataFrame(table)` makes a frame of it):

    import hapto
    scene = hapto.default_scene()
    path = numpy.column_stack([numpy.linspace(-0.1, 0.1, 200), numpy.zeros(200), numpy.zeros(200)])
    forces = hapto.render(scene, path)            # = hapto render --path ... (columns)
    with hapto.Session(scene, stepped=True) as s: # the two simulated hands, step mode
        s.step(1000)
        report = s.report()                        # = hapto run --report's JSON

Dynamic bodies (a version-3 scene, or dynamic_grasp_scene()) run with the session:

    with hapto.Session(hapto.dynamic_grasp_scene("box"), devices=[], stepped=True,
                       record="runs") as s:  # = hapto run --no-devices --stepped --record runs
        s.step(500)                            # 500 dynamics steps (no device)
        poses = s.bodies()                     # id, center (N, 3), rotation (N, 4) w,x,y,z, ...
    trace = hapto.read_trace("runs/bodies.trace")  # = hapto trace export runs/bodies.trace

Bad input raises hapto.InputError (a ValueError) with the message the command prints after
"hapto: "; other failures raise RuntimeError.
"""

import json as _json
import os as _os
import tempfile as _tempfile

from . import _hapto
from ._hapto import (
    Index,
    InputError,
    Scene,
    build_index,
    cluster_scene,
    default_scene,
    dynamic_grasp_scene,
    grasp_scene,
    lattice_scene,
    load_scene,
    random_scene,
    read_trace,
    render,
    trace_header,
)

__version__ = _hapto.__version__

__all__ = [
    "Index", "InputError", "Scene", "Session", "build_index", "cluster_scene", "default_scene",
    "dynamic_grasp_scene", "experiment_grasp", "experiment_scaling", "grasp_scene", "lattice_scene", "load_scene", "random_scene",
    "read_trace", "render", "trace_header", "__version__",
]


class Session:
    """A session of devices over one shared world (the library's Runtime and Session).

    devices: None (the two simulated hands `hapto run` drives by default), a device file's
    path, a list of dicts like a device file's `devices` entries, or [] (no device: only the
    dynamics runs, as `hapto run --no-devices`; the scene needs a dynamic body). stepped: step
    mode (the session's own clock: the same result every run; only simulated hands and
    replays). record: a folder to write the dynamic bodies' trace into (DIR/bodies.trace, as
    `hapto run --record DIR` does; the devices' traces are not written from Python).
    index: an index spec text (None: the default); rate_hz: every device's rate (None: each
    device's own); realtime: ask for SCHED_FIFO and pinning (off by default here).
    The GIL is released while the session runs; Ctrl-C stops it at zero force.
    """

    def __init__(self, scene, devices=None, stepped=False, index=None, rate_hz=None,
                 realtime=False, max_index_mb=None, record=None):
        kwargs = {"stepped": stepped, "index": index or "", "rate_hz": rate_hz or 0.0,
                  "realtime": realtime}
        if record is not None:
            kwargs["record"] = _os.fspath(record)
        if max_index_mb is not None:
            kwargs["max_index_mb"] = max_index_mb
        if devices is None:
            pass
        elif isinstance(devices, (str, _os.PathLike)):
            kwargs["devices_path"] = _os.fspath(devices)
        elif len(devices) == 0:
            kwargs["no_devices"] = True
        else:
            kwargs["devices_json"] = _json.dumps(
                {"format": "hapto-devices", "version": 1, "devices": list(devices)})
        self._session = _hapto.Session(scene, **kwargs)

    def run(self, seconds):
        """Runs for `seconds` of session time (s); returns why it ended ("finished", ...)."""
        return self._session.run(seconds)

    def step(self, ticks):
        """Step mode only: runs `ticks` ticks of the fastest device (with no device, `ticks`
        dynamics steps); returns why it ended."""
        return self._session.step(ticks)

    def bodies(self):
        """The dynamic bodies' latest poses (from the first run() or step() on), one row per
        body in the scene's slot order, as a dict of numpy arrays: id, center (N, 3; the scene
        object's centre, m), rotation (N, 4; w, x, y, z), center_of_mass (N, 3; m), velocity
        (N, 3; of the centre of mass, m/s), angular_velocity (N, 3; rad/s), sleeping, time_s
        (the pose's session time, s) and step (the dynamics step that made it)."""
        return self._session.bodies()

    body_poses = bodies

    def report(self):
        """The run report as a dict: what `hapto run --report` writes."""
        return _json.loads(self._session.report_json())

    def stop(self):
        """Zero force on every device, devices closed; returns the final report (a dict)."""
        return _json.loads(self._session.stop())

    @property
    def time_s(self):
        """Session time (s) since the devices started."""
        return self._session.time_s

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()
        return False


def _columns(rows):
    """A list of JSON objects as a dict of numpy arrays, keyed in the first row's order."""
    import numpy

    names = list(rows[0].keys()) if rows else []
    return {n: numpy.asarray([r.get(n) for r in rows]) for n in names}


def experiment_scaling(out=None, **options):
    """`hapto experiment scaling` (load against device count; cursor steps against N).

    Writes its files into `out` (None: a temporary folder, removed after) and returns its
    tables as dicts of numpy arrays: "devices" (a row per rate and device count),
    "per_device" (a row per device of each cell) and "cursor". Options are the command's, in
    snake case: max_devices, counts (device counts, e.g. range(1, 9); default 1, 2, 4, ... up
    to max_devices), rates_hz, scene, index, script, cursor_objects, walk_steps, cursor, quick,
    duration_s, repeats (default 5), realtime. Each cell of "devices" holds the median over the
    repeats and its order-statistic interval (the *_lo_pct and *_hi_pct columns, and
    interval_coverage). It runs real servo threads on the wall clock.
    """
    with _tempfile.TemporaryDirectory(prefix="hapto-experiment-") as tmp:
        folder = _os.fspath(out) if out is not None else tmp
        code = _hapto.run_devices(folder, **options)
        if code != 0:
            raise RuntimeError("hapto experiment scaling ended with exit code %d" % code)
        with open(_os.path.join(folder, "devices.json"), encoding="utf-8") as f:
            result = _json.load(f)
    cells = result["devices"]
    per_device = [d for cell in cells for d in cell.get("per_device", [])]
    table = [{k: v for k, v in cell.items() if k != "per_device"} for cell in cells]
    return {"devices": _columns(table), "per_device": _columns(per_device),
            "cursor": _columns(result.get("cursor", []))}


experiment_devices = experiment_scaling


def experiment_grasp(out=None, quick=False, squeezes_n=None, masses_kg=None,
                     stiffnesses_n_per_m=None, rates_hz=None, repeats=None):
    """`hapto experiment grasp` (two simulated hands grasp, lift and carry a dynamic box in step
    mode, one factor swept at a time around a default cell).

    Writes its files into `out` (None: a temporary folder, removed after) and returns its table
    (grasp.csv's rows) as a dict of numpy arrays. quick: the command's --quick smoke subset
    (two cells, one run each); a list given (squeezes_n in N a hand, masses_kg, stiffnesses_n_per_m
    in N/m, rates_hz) replaces the subset's or the default's, as the command's options do.
    repeats: runs per cell (default 5, quick 1). Each cell is about 7 s of simulated time.
    """
    lists = {"squeezes_n": squeezes_n, "masses_kg": masses_kg,
             "stiffnesses_n_per_m": stiffnesses_n_per_m, "rates_hz": rates_hz}
    kwargs = {k: [float(v) for v in vs] for k, vs in lists.items() if vs is not None}
    for k, vs in kwargs.items():
        if not vs:
            raise InputError("%s: an empty list; give at least one value or None" % k)
    with _tempfile.TemporaryDirectory(prefix="hapto-experiment-") as tmp:
        folder = _os.fspath(out) if out is not None else tmp
        code = _hapto.run_grasp(folder, quick=quick, repeats=repeats, **kwargs)
        if code != 0:
            raise RuntimeError("hapto experiment grasp ended with exit code %d" % code)
        with open(_os.path.join(folder, "grasp.json"), encoding="utf-8") as f:
            result = _json.load(f)
    return _columns(result["rows"])
