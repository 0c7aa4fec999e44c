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
them (a value of None removes the field). Every bad input or rejected command raises SceneError
(a ValueError) whose `field`, `value` and `allowed` say what is wrong; a rejected command leaves
the simulation as it was. Statistics are the same JSON as simulate_pass's stats.json, as a dict.
"""
import json
import math
import numbers
import operator
import re
import os
import time
from pkgutil import extend_path

import numpy as np
import yaml

# The package lives in two places: these sources and the build's devel space (the pybind11
# extension _core, the generated message modules). A process that meets the sources first on
# sys.path (a Dask worker spawned from a sourced shell) must still find the rest.
__path__ = extend_path(__path__, __name__)

from . import _core  # noqa: E402

__all__ = ["SceneError", "Simulation", "run_pass", "check_scene"]

_FIELD = re.compile(r"scene field '(?P<field>[^']*)' = (?P<value>.*?): (?P<allowed>.*)$", re.S)
_OVERRIDE = re.compile(r"override '(?P<field>[^'=]*)=(?P<value>[^']*)': (?P<allowed>.*)$", re.S)
_ALLOWED = re.compile(r"rejected: (?:allowed )?(?P<allowed>.*)$", re.S)

# A scene or an override value given as Python objects is written out as YAML for the core. Far
# beyond any real scene (a few levels, some thousand values) but bounded, so that a deep or
# self-multiplying structure is refused at once instead of exhausting the stack or the memory.
MAX_DEPTH = 32
MAX_VALUES = 1_000_000


class SceneError(ValueError):
    """A scene, override, argument or command that cannot be used.

    Attributes: field (the scene field, e.g. "pantographs[0].static_uplift", or the argument,
    e.g. "speed_mps"; None when the message names only a file), value (as given: the text of a
    scene's value, repr() of a Python argument), allowed (what would be accepted), message (all of it).
    """

    def __init__(self, message, field=None, value=None, allowed=None):
        super().__init__(message)
        self.message = message
        self.field, self.value, self.allowed = field, value, allowed
        if field is None:
            for pattern in (_FIELD, _OVERRIDE):
                m = pattern.search(message)
                if m:
                    self.field, self.value, self.allowed = m.group("field"), m.group("value"), m.group("allowed")
                    break


def _refuse(name, value, allowed, why=None):
    shown = _shown(value)
    raise SceneError(f"{name} = {shown} rejected: {why + '; ' if why else ''}allowed {allowed}",
                     field=name, value=shown, allowed=allowed) from None


def _shown(value):
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _scalar(value):
    """numpy scalars and 0-d arrays as the Python numbers they hold; anything else as it is."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, np.generic):
        value = value.item()
    return value


def _real(name, value, allowed="a finite number", low=-math.inf, high=math.inf):
    """A number argument as a float (numpy numbers too), refused unless finite and in [low, high]."""
    v = _scalar(value)
    if isinstance(v, bool) or not isinstance(v, numbers.Real):
        _refuse(name, value, allowed, "not a number")
    try:
        f = float(v)
    except (OverflowError, ValueError, TypeError):
        _refuse(name, value, allowed, "not a number")
    if not (math.isfinite(f) and low <= f <= high):
        _refuse(name, value, allowed)
    return f


def _integer(name, value, allowed, low, high, whole_floats=False):
    """An integer argument (numpy integers too; whole floats if asked), refused outside [low, high]."""
    v = _scalar(value)
    if whole_floats and isinstance(v, float) and math.isfinite(v) and v.is_integer():
        v = int(v)
    if isinstance(v, bool):
        _refuse(name, value, allowed, "not an integer")
    try:
        i = operator.index(v)
    except TypeError:
        _refuse(name, value, allowed, "not an integer")
    if not low <= i <= high:
        _refuse(name, value, allowed)
    return i


def _path(name, value, allowed):
    if isinstance(value, (str, os.PathLike)):
        p = os.fspath(value)
        if isinstance(p, str):
            return p
    _refuse(name, value, allowed, f"of type {type(value).__name__}")


def _plain(value, field, origin):
    """value as plain Python data for YAML (numpy numbers as numbers, arrays and tuples as lists,
    every shared object written out in full). A value that cannot be written, contains itself, nests
    deeper than MAX_DEPTH or holds more than MAX_VALUES values is refused naming the scene field
    where it is (field: the value's own field, "" for a whole scene; origin: "scene" or "override")."""
    budget = [MAX_VALUES]
    open_ = set()  # the containers being written out: meeting one again means it contains itself

    def refuse(at, shown, why, allowed):
        name = at or "scene"
        raise SceneError(f"{origin} field '{name}' = {shown}: {why}; allowed {allowed}",
                         field=name, value=shown, allowed=allowed)

    def walk(v, at, depth):
        budget[0] -= 1
        if budget[0] < 0:
            top = re.split(r"[.\[]", at, maxsplit=1)[0] if at else ""
            refuse(top, "...", f"more than {MAX_VALUES} values (an object used n times counts n times)",
                   f"at most {MAX_VALUES} values")
        v = _scalar(v)
        if v is None or isinstance(v, (bool, str)):
            return v
        if isinstance(v, numbers.Integral):
            return int(v)
        if isinstance(v, numbers.Real):
            return float(v)
        if isinstance(v, np.ndarray):
            v = v.tolist()
        if not isinstance(v, (dict, list, tuple)):
            refuse(at, _shown(v), f"of type {type(v).__name__}", "a number, a string, a bool, None, a list or a dict")
        if depth >= MAX_DEPTH:
            refuse(at, "...", f"nested deeper than {MAX_DEPTH} levels", f"at most {MAX_DEPTH} levels of lists and dicts")
        if id(v) in open_:
            refuse(at, "...", f"the {type(v).__name__} contains itself", "a list or a dict that does not contain itself")
        open_.add(id(v))
        try:
            if isinstance(v, dict):
                out = {}
                for k, item in v.items():
                    if not isinstance(k, str):
                        refuse(at, _shown(k), f"a key of type {type(k).__name__}", "field names (strings) as keys")
                    out[k] = walk(item, f"{at}.{k}" if at else k, depth + 1)
                return out
            return [walk(item, f"{at}[{i}]", depth + 1) for i, item in enumerate(v)]
        finally:
            open_.discard(id(v))

    return walk(value, field, 0)


class _Dumper(yaml.SafeDumper):
    def ignore_aliases(self, data):  # _plain made a tree: nothing to alias, and readers need none
        return True


def _yaml(value, flow):
    return yaml.dump(value, Dumper=_Dumper, sort_keys=False, default_flow_style=flow, width=math.inf,
                     allow_unicode=True)


def _override_list(overrides):
    if overrides is None:
        return []
    if isinstance(overrides, dict):
        out = []
        for key, value in overrides.items():
            if not isinstance(key, str) or not key or "=" in key:
                _refuse("overrides", key, "dotted scene keys as strings, without '=' (e.g. 'train.speed_kmh')",
                        "a key")
            text = _yaml(_plain(value, key, "override"), True).strip()
            if text.endswith("..."):
                text = text[:-3].strip()
            out.append(f"{key}={text}")
        return out
    if isinstance(overrides, (list, tuple)):
        for i, o in enumerate(overrides):
            if not isinstance(o, str) or not o.split("=", 1)[0].strip() or "=" not in o:
                _refuse(f"overrides[{i}]", o, "a 'dotted.key=value' string")
        return list(overrides)
    _refuse("overrides", overrides, "a dict {'dotted.key': value} or a list of 'dotted.key=value' strings")


def _with_speed(overrides, speed_kmh):
    if speed_kmh is None:
        return overrides
    v = _real("speed_kmh", speed_kmh, "a speed in km/h (a finite number)")
    return overrides + ["train.speed=null", f"train.speed_kmh={v!r}"]


_SCENE = "a YAML file path (str or os.PathLike) or a dict of the scene's fields"


def _scene_text(scene):
    if isinstance(scene, dict):
        return _yaml(_plain(scene, "", "scene"), False)
    _refuse("scene", scene, _SCENE)


def _scene_path(scene):
    """The path of a scene given as one, or None for a dict (anything else is refused)."""
    if isinstance(scene, dict):
        return None
    return _path("scene", scene, _SCENE)


def _translate(call, speed_kmh=None):
    try:
        return call()
    except ValueError as e:  # _core._SceneError is a ValueError; commands raise ValueError too
        if isinstance(e, SceneError):
            raise
        err = SceneError(str(e))
        if speed_kmh is not None and err.field == "train.speed_kmh":
            err.field = "speed_kmh"  # the argument that set it
        raise err from None


def _command(call, argument, value):
    """A command of the core; its refusal (ValueError with the allowed range) as SceneError."""
    try:
        return call()
    except ValueError as e:
        m = _ALLOWED.search(str(e))
        raise SceneError(str(e), field=argument, value=_shown(value),
                         allowed=m.group("allowed") if m else str(e)) from None


class Simulation:
    """One pass of a scene, stepped at its fixed dt (the core's Simulation).

    scene: a path (str or os.PathLike) or a dict; overrides: dict or list (as simulate_pass --set);
    speed_kmh: overrides the train speed; sample_rate: Hz of the recorded time series (None: the
    scene's output.sample_rate; 0: every step). One object may be used from several threads: each
    call acts on the pass as a whole, one at a time (step() and run() let other threads run).
    """

    def __init__(self, scene, overrides=None, speed_kmh=None, sample_rate=None):
        ov = _with_speed(_override_list(overrides), speed_kmh)
        if sample_rate is None:
            rate = -1.0  # the scene's output.sample_rate
        else:
            rate = _real("sample_rate", sample_rate, "a finite number >= 0 Hz (0: every step)", 0.0)
        path = _scene_path(scene)
        if path is not None:
            self._sim = _translate(lambda: _core._Simulation.from_file(path, ov, rate), speed_kmh)
        else:
            text = _scene_text(scene)
            self._sim = _translate(lambda: _core._Simulation(text, ov, rate), speed_kmh)

    # Stepping ------------------------------------------------------------------------------
    def step(self, n=1):
        """Steps up to n times (stops at the end of the pass); returns the steps taken.
        Raises RuntimeError if the watchdog stopped a diverging pass."""
        return self._sim.step(_integer("n", n, "an integer from 0 to 2**63 - 1", 0, 2 ** 63 - 1, whole_floats=True))

    def run(self, max_steps=2e7):
        """Steps to the end of the pass; returns the steps taken. Refuses (SceneError) a pass that
        would take more than max_steps (speed 0 never ends), as simulate_pass --max-steps does."""
        limit = _real("max_steps", max_steps, "a finite number >= 0", 0.0)
        return _command(lambda: self._sim.run(limit), "max_steps", max_steps)

    def finished(self):
        return self._sim.finished()

    def reset(self):
        """A new pass from the start (time keeps running; commands and the sample rate stay in effect)."""
        self._sim.reset()

    # Results -------------------------------------------------------------------------------
    def statistics(self, wall_time_s=0.0):
        """The pass statistics so far, as simulate_pass's stats.json (a dict)."""
        wall = _real("wall_time_s", wall_time_s, "a finite number of seconds >= 0", 0.0)
        return json.loads(self._sim.statistics_json(wall))

    def write_files(self, directory, wall_time_s=0.0):
        """Writes the pass's files into `directory` (str or os.PathLike) as simulate_pass --out
        does (stats.json, timeseries.csv, the measurement CSVs), each whole or not at all;
        scripts/pass_report draws the report from them. Raises ValueError naming a file that
        cannot be written."""
        path = _path("directory", directory, "a directory path (str or os.PathLike)")
        wall = _real("wall_time_s", wall_time_s, "a finite number of seconds >= 0", 0.0)
        self._sim.write_pass_files(path, wall)

    def series(self):
        """The recorded time series as numpy arrays by column name (time_s, <pantograph>_force_N, ...)."""
        return self._sim.series()

    def pantograph_state(self, index=0):
        i = _integer("index", index, self._index_range(), 0, len(self._sim.pantograph_names) - 1)
        return self._sim.pantograph_state(i)

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

    # Commands (checked; a rejected one raises SceneError and changes nothing) -------------------
    def set_speed(self, speed_mps):
        v = _real("speed_mps", speed_mps,
                  f"0 to below the contact wire's wave speed, at most {_core._MAX_SPEED:g} m/s")
        _command(lambda: self._sim.set_speed(v), "speed_mps", speed_mps)

    def set_max_acceleration(self, accel_mps2):
        a = _real("accel_mps2", accel_mps2, "0 (no limit) to 20 m/s^2")
        _command(lambda: self._sim.set_max_acceleration(a), "accel_mps2", accel_mps2)

    def set_uplift(self, force_n, pantograph=-1):
        """The static uplift of one pantograph (its index), or of every one (-1)."""
        f = _real("force_n", force_n, f"0 to {_core._MAX_UPLIFT:g} N")
        n = len(self._sim.pantograph_names)
        i = _integer("pantograph", pantograph, self._index_range() + ", or -1 for every pantograph", -1, n - 1)
        _command(lambda: self._sim.set_uplift(f, i), "force_n", force_n)

    def set_external_force(self, force_n, pantograph=0):
        """The measured contact force of an external (hardware-in-the-loop) pantograph."""
        f = _real("force_n", force_n, f"{_core._MIN_EXTERNAL_FORCE:g} to {_core._MAX_EXTERNAL_FORCE:g} N")
        external = self._sim.external_pantographs
        if external:
            allowed = "an external (hardware-in-the-loop) pantograph's index: " + ", ".join(map(str, external))
        else:
            allowed = "none: the scene has no external (hardware-in-the-loop) pantograph"
        i = _integer("pantograph", pantograph, allowed, 0, len(self._sim.pantograph_names) - 1)
        if i not in external:
            _refuse("pantograph", pantograph, allowed, "not an external pantograph")
        _command(lambda: self._sim.set_external_force(f, i), "force_n", force_n)

    def _index_range(self):
        n = len(self._sim.pantograph_names)
        return f"an integer from 0 to {n - 1} (the scene has {n} pantograph{'s' if n != 1 else ''})"


def check_scene(scene, overrides=None):
    """Loads and validates a scene (a path or a dict) without building it; raises SceneError."""
    ov = _override_list(overrides)
    path = _scene_path(scene)
    if path is not None:
        _translate(lambda: _core._check_scene_file(path, ov))
    else:
        text = _scene_text(scene)
        _translate(lambda: _core._check_scene_string(text, ov, ""))


def run_pass(scene, overrides=None, speed_kmh=None, sample_rate=None):
    """A whole pass: returns (statistics dict, time series dict of numpy arrays).

    sample_rate: Hz of the series (default None: the scene's output.sample_rate; 0: every step)."""
    sim = Simulation(scene, overrides, speed_kmh, sample_rate)
    start = time.perf_counter()
    sim.run()
    return sim.statistics(time.perf_counter() - start), sim.series()
