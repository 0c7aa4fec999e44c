"""catenary_sim from Python: scenes, passes and stepping on the C++ core (pybind11).

    import catenary_sim as cs
    stats, series = cs.run_pass("config/reference_55m.yaml", overrides={"train.speed_kmh": 250})
    stats["pantographs"][0]["std_force_N"], series["time_s"], series["leading_force_N"]

    sim = cs.Simulation({"name": "wire", "line": {...}, ...})    # a scene as a dict
    sim.step(1000)                                               # steps of the fixed dt
    sim.displacements, sim.contact_forces                        # numpy views of the state
    sim.set_speed(80.0); sim.set_uplift(120.0)                   # commands, checked

A scene is a YAML file path or a dict with the same fields (docs/scene_reference.md); overrides are
a dict {"dotted.key": value} or a list of "dotted.key=value" strings, as simulate_pass --set takes
them (a value of None removes the field). Every bad input raises SceneError (a ValueError) whose
`field`, `value` and `allowed` say what is wrong; a rejected command raises ValueError and leaves
the simulation as it was. Statistics are the same JSON as simulate_pass's stats.json, as a dict.
"""
import json
import re
import os
import time
from pkgutil import extend_path

import yaml

# The package lives in two places: these sources and the build's devel space (the pybind11
# extension _core, the generated message modules). A process that meets the sources first on
# sys.path (a Dask worker spawned from a sourced shell) must still find the rest.
__path__ = extend_path(__path__, __name__)

from . import _core  # noqa: E402

__all__ = ["SceneError", "Simulation", "run_pass", "check_scene"]

_FIELD = re.compile(r"scene field '(?P<field>[^']*)' = (?P<value>.*?): (?P<allowed>.*)$", re.S)
_OVERRIDE = re.compile(r"override '(?P<field>[^'=]*)=(?P<value>[^']*)': (?P<allowed>.*)$", re.S)


class SceneError(ValueError):
    """A scene, override or command that cannot be used.

    Attributes: field (the scene field, e.g. "pantographs[0].static_uplift", or None when the
    message names a file), value (as given), allowed (what would be accepted), message (all of it).
    """

    def __init__(self, message):
        super().__init__(message)
        self.message = message
        self.field = self.value = self.allowed = None
        for pattern in (_FIELD, _OVERRIDE):
            m = pattern.search(message)
            if m:
                self.field, self.value, self.allowed = m.group("field"), m.group("value"), m.group("allowed")
                break


def _override_list(overrides):
    if overrides is None:
        return []
    if isinstance(overrides, dict):
        out = []
        for key, value in overrides.items():
            text = "null" if value is None else yaml.safe_dump(value, default_flow_style=True).strip()
            if text.endswith("\n...") or text.endswith("..."):
                text = text.rsplit("...", 1)[0].strip()
            out.append(f"{key}={text}")
        return out
    if isinstance(overrides, (list, tuple)):
        for o in overrides:
            if not isinstance(o, str):
                raise SceneError(f"override {o!r}: expected a 'dotted.key=value' string")
        return list(overrides)
    raise SceneError(f"overrides: expected a dict or a list of 'key=value' strings, got {type(overrides).__name__}")


def _with_speed(overrides, speed_kmh):
    if speed_kmh is None:
        return overrides
    return overrides + ["train.speed=null", f"train.speed_kmh={float(speed_kmh)!r}"]


def _scene_text(scene):
    if isinstance(scene, dict):
        return yaml.safe_dump(scene, sort_keys=False)
    raise SceneError(f"scene: expected a YAML file path or a dict, got {type(scene).__name__}")


def _translate(call):
    try:
        return call()
    except ValueError as e:  # _core._SceneError is a ValueError; commands raise ValueError too
        if isinstance(e, SceneError):
            raise
        raise SceneError(str(e)) from None


class Simulation:
    """One pass of a scene, stepped at its fixed dt (the core's Simulation).

    scene: a path or a dict; overrides: dict or list (as simulate_pass --set); speed_kmh: overrides
    the train speed; sample_rate: Hz of the recorded time series (None: the scene's
    output.sample_rate; 0: every step).
    """

    def __init__(self, scene, overrides=None, speed_kmh=None, sample_rate=None):
        ov = _with_speed(_override_list(overrides), speed_kmh)
        if sample_rate is None:
            sample_rate = -1.0  # the scene's output.sample_rate
        elif not (float(sample_rate) >= 0.0 and float(sample_rate) < float("inf")):
            raise SceneError(f"sample_rate = {sample_rate!r}: allowed >= 0 Hz (0: every step)")
        if isinstance(scene, str):
            self._sim = _translate(lambda: _core._Simulation.from_file(scene, ov, float(sample_rate)))
        else:
            text = _scene_text(scene)
            self._sim = _translate(lambda: _core._Simulation(text, ov, float(sample_rate)))

    # Stepping ------------------------------------------------------------------------------
    def step(self, n=1):
        """Steps up to n times (stops at the end of the pass); returns the steps taken.
        Raises RuntimeError if the watchdog stopped a diverging pass."""
        return self._sim.step(int(n))

    def run(self, max_steps=2e7):
        """Steps to the end of the pass; returns the steps taken. Refuses (ValueError) a pass that
        would take more than max_steps (speed 0 never ends), as simulate_pass --max-steps does."""
        return self._sim.run(float(max_steps))

    def finished(self):
        return self._sim.finished()

    def reset(self):
        """A new pass from the start (time keeps running; commands stay in effect)."""
        self._sim.reset()

    # Results -------------------------------------------------------------------------------
    def statistics(self, wall_time_s=0.0):
        """The pass statistics so far, as simulate_pass's stats.json (a dict)."""
        return json.loads(self._sim.statistics_json(float(wall_time_s)))

    def write_files(self, directory, wall_time_s=0.0):
        """Writes the pass's files into `directory` as simulate_pass --out does (stats.json,
        timeseries.csv, the measurement CSVs), each whole or not at all; scripts/pass_report draws
        the report from them. Raises ValueError naming a file that cannot be written."""
        self._sim.write_pass_files(str(directory), float(wall_time_s))

    def series(self):
        """The recorded time series as numpy arrays by column name (time_s, <pantograph>_force_N, ...)."""
        return self._sim.series()

    def pantograph_state(self, index=0):
        return self._sim.pantograph_state(index)

    # Views of the state (numpy, read-only, updated in place as the simulation steps) -------------
    displacements = property(lambda self: self._sim.displacements, doc="generalized displacements q (m), per DOF")
    velocities = property(lambda self: self._sim.velocities, doc="half-step velocities (m/s), per DOF")
    contact_forces = property(lambda self: self._sim.contact_forces, doc="N, per collector x contact wire")
    time = property(lambda self: self._sim.time, doc="s since the pass started")
    steps = property(lambda self: self._sim.steps)
    dt = property(lambda self: self._sim.dt, doc="s, the fixed time step")
    dofs = property(lambda self: self._sim.dofs)
    speed = property(lambda self: self._sim.speed, doc="m/s")
    front = property(lambda self: self._sim.front, doc="m, train front along the line")
    status = property(lambda self: self._sim.status)
    pantograph_names = property(lambda self: self._sim.pantograph_names)
    contact_wire_names = property(lambda self: self._sim.contact_wire_names)
    steady_arms = property(lambda self: self._sim.steady_arms,
                           doc="list of dicts per steady arm: wire, station_m (model stations; on an endless line "
                               "add the line offset, a wire_shape's stations[0] - wire_start_m), design_height_m, "
                               "wire_start_m")

    # Commands (checked; a rejected one raises ValueError and changes nothing) -------------------
    def set_speed(self, speed_mps):
        self._sim.set_speed(float(speed_mps))

    def set_max_acceleration(self, accel_mps2):
        self._sim.set_max_acceleration(float(accel_mps2))

    def set_uplift(self, force_n, pantograph=-1):
        self._sim.set_uplift(float(force_n), int(pantograph))

    def set_external_force(self, force_n, pantograph=0):
        self._sim.set_external_force(float(force_n), int(pantograph))


def check_scene(scene, overrides=None):
    """Loads and validates a scene without building it; raises SceneError."""
    ov = _override_list(overrides)
    if isinstance(scene, str):
        with open(scene, "rb") as f:
            text = f.read(16 << 20).decode("utf-8", errors="replace")
        base = os.path.dirname(os.path.abspath(scene))  # profiles (csv) are looked up beside the scene
    else:
        text = _scene_text(scene)
        base = ""
    _translate(lambda: _core._check_scene_string(text, ov, base))


def run_pass(scene, overrides=None, speed_kmh=None, sample_rate=None):
    """A whole pass: returns (statistics dict, time series dict of numpy arrays).

    sample_rate: Hz of the series (default None: the scene's output.sample_rate; 0: every step)."""
    sim = Simulation(scene, overrides, speed_kmh, sample_rate)
    start = time.perf_counter()
    sim.run()
    return sim.statistics(time.perf_counter() - start), sim.series()
