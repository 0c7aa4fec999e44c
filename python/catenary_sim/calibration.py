"""Calibration: the scene parameters a measured record is best reproduced with, their uncertainty,
and which of them the record cannot identify.

    scripts/calibrate CALIBRATION.yaml --out DIR [--workers 2 | --scheduler tcp://host:8786]
    from catenary_sim.calibration import calibrate; result = calibrate("CALIBRATION.yaml", "DIR")

A calibration file (YAML; paths relative to it):

    scene: ../config/reference_55m.yaml
    record: measured_run.csv            # its metadata beside it (measured_run.yaml) or in '#' lines
    overrides: {}                       # applied to every evaluation, as simulate_pass --set
    speed_profile: null                 # null: the record's; a speed in km/h
    cutoff: scene                       # the comparison's low-pass: scene, bandwidth or Hz
    parameters:                         # any scene field, with its bounds
      - {key: damping.beta, low: 5.0e-5, high: 1.0e-3, scale: log}       # scale: linear (default) or log
      - {key: droppers.axial_stiffness, low: 2.0e+4, high: 4.0e+5, scale: log}
    objective:                          # weights; the residuals are squared and summed
      statistics: {std_force_N: 1, max_force_N: 1, min_force_N: 1}       # relative deviations
      time_history: 1                   # (simulated - record) / std(record), rms over the section
      spectrum: 0                       # dB differences up to the cutoff, rms
    optimiser: {method: least_squares, max_evaluations: 60}   # or minimize:Nelder-Mead, minimize:Powell
                                        # max_evaluations: the passes run, Jacobians' and uncertainty's too

Every evaluation is catenary_sim.measurement.compare with the parameters as overrides, run on a
Dask cluster (a local one of --workers processes by default) and written atomically to
DIR/evaluations/ keyed by its parameter values and a digest of everything else that decides it
(scene and record text, overrides, speed profile, cutoff, objective), so that the same calibration
started again on the same DIR replays them and goes on where it stopped, and another one never does. Writes DIR/calibrated.yaml (the scene snippet),
DIR/calibration.json (values, uncertainties, identifiability, residuals before and after) and
DIR/before/ and DIR/after/ (compare_measurement's report at the initial and calibrated values).
"""
import hashlib
import json
import math
import os

import numpy as np
import yaml
from scipy import optimize

from . import SceneError
from . import measurement as cm
from ._files import write_atomically
from .study import TEXT_NUMBER_HINT, _StrictLoader, _check_output_dir, _check_path, _check_workers, _make_output_dir

METHODS = ("least_squares", "minimize:Nelder-Mead", "minimize:Powell")
FIELDS = {"scene", "record", "meta", "overrides", "speed_profile", "cutoff", "parameters", "objective", "optimiser"}
# Forward differences in the parameters' unit scale (bounds mapped to [0, 1]): a step of 1 % of the
# range, far above the passes' rounding (they are deterministic to the last bit) and small against
# the curvature of the deviations over the range.
DIFF_STEP = 0.01
# A direction of the parameters whose singular value is below this share of the largest changes the
# residuals a thousand times less than the best-determined one: the record does not fix it.
IDENTIFIABLE_SV = 1e-3
# The residuals one difference step on the other side of the optimum may depart from the Jacobian's
# straight line by this share of the step's change: a smooth objective departs by the curvature
# over 1 % of the range (a few per cent); a rough one (a coarse preset, where the last bit of a
# parameter moves the objective by tens of per cent) by about the whole change or more.
LINEAR_RATIO = 0.5


class CalibrationError(ValueError):
    """A calibration file that cannot be run: names the field, the value and what is allowed."""


def _fail(field, value, allowed):
    raise CalibrationError(f"calibration field '{field}' = {value!r}: {allowed}")


class _Loader(_StrictLoader):
    """The study files' YAML reader: a key given twice in one map, or an alias, is refused."""
    error, what = CalibrationError, "calibration file"


def _number(v, field, allowed, positive=False):
    # A number as YAML reads it, as in a study file: text (2.0e4, which YAML 1.1 reads as text, or
    # a quoted number) is refused with how to write it.
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or (positive and v <= 0):
        _fail(field, v, allowed + (", " + TEXT_NUMBER_HINT if isinstance(v, str) else ""))
    return float(v)


def _weight(w, field):
    # A weight is a number as YAML reads it: text ("1e0", quoted or without a dot) is refused.
    if isinstance(w, bool) or not isinstance(w, (int, float)) or not math.isfinite(w) or w < 0:
        _fail(field, w, "a weight: a finite number >= 0, not text (YAML 1.1 reads 1e0 as text: write 1.0)")
    return float(w)


def measurable(cal, record):
    """Refuses an objective that asks for a statistic the record cannot give: its residual would
    never be formed (the head's without a head column, the steady arms' uplift without supports)."""
    needs = {n: ("a head_PANTOGRAPH column", bool(record.head_m)) for n in cm.HEAD}
    needs.update({n: ("supports with uplift_SUPPORT columns", bool(record.uplift_m)) for n in cm.UPLIFT})
    for k, w in cal["objective"]["statistics"].items():
        if w and k in needs and not needs[k][1]:
            _fail(f"objective.statistics.{k}", w, f"a statistic the record has: it needs {needs[k][0]}, "
                  f"which {cal['record']} has not")


def load_calibration(path):
    """Reads and checks a calibration file; returns a dict with absolute paths."""
    try:
        with open(path, encoding="utf-8") as f:
            doc = _Loader.load(f.read(), path)
    except (OSError, yaml.YAMLError, UnicodeDecodeError, RecursionError) as e:
        raise CalibrationError(f"calibration file {path!r} cannot be read: {e}") from None
    if not isinstance(doc, dict):
        _fail("", doc, "a YAML map (scene, record, parameters, objective, ...)")
    for k in doc:
        if k not in FIELDS:
            _fail(k, doc[k], "not a field; allowed " + ", ".join(sorted(FIELDS)))
    base = os.path.dirname(os.path.abspath(path))
    out = dict(doc)
    out["path"] = os.path.abspath(path)
    for k in ("scene", "record"):
        if not isinstance(doc.get(k), str):
            _fail(k, doc.get(k), "a file path (relative to the calibration file)")
        out[k] = os.path.join(base, doc[k])
    if doc.get("meta") is not None and not isinstance(doc["meta"], str):
        _fail("meta", doc["meta"], "null (beside the record or in its '#' lines) or a YAML file path")
    out["meta"] = os.path.join(base, doc["meta"]) if isinstance(doc.get("meta"), str) else None
    # A section left empty (null) takes its default; anything but a map is refused, not read as one.
    ov = {} if doc.get("overrides") is None else doc["overrides"]
    if not isinstance(ov, dict):
        _fail("overrides", ov, "a map {dotted.key: value} (or null: none)")
    out["overrides"] = ov
    v = out["speed_profile"] = doc.get("speed_profile")
    # Numbers as YAML reads them: text ("300") is refused rather than read as one.
    if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v <= 540):
        _fail("speed_profile", v, "null (the record's) or a speed in km/h, 0 < v <= 540 (not text)")
    c = out["cutoff"] = doc.get("cutoff", "scene")
    if c not in ("scene", "bandwidth") and (isinstance(c, bool) or not isinstance(c, (int, float))
                                             or not math.isfinite(c) or c <= 0):
        _fail("cutoff", c, "scene, bandwidth or a frequency in Hz > 0 (not text)")
    params = doc.get("parameters")
    if not isinstance(params, list) or not params:
        _fail("parameters", params, "a list of {key, low, high, scale}")
    keys = set()
    for i, p in enumerate(params):
        where = f"parameters[{i}]"
        if not isinstance(p, dict) or not isinstance(p.get("key"), str) or not p["key"]:
            _fail(where, p, "a map with key (a scene field), low, high and optionally scale and initial")
        if p["key"] in keys:
            _fail(where + ".key", p["key"], "each parameter once")
        keys.add(p["key"])
        lo = p["low"] = _number(p.get("low"), where + ".low", "a finite number")
        hi = p["high"] = _number(p.get("high"), where + ".high", "a finite number above low")
        scale = p.get("scale", "linear")
        if scale not in ("linear", "log"):
            _fail(where + ".scale", scale, "linear or log")
        if not lo < hi or (scale == "log" and lo <= 0):
            _fail(where, p, "low < high (both > 0 on a log scale)")
        if "initial" in p:
            v = p["initial"] = _number(p["initial"], where + ".initial", "a number within [low, high]")
            if not lo <= v <= hi:
                _fail(where + ".initial", v, f"within [{lo:g}, {hi:g}]")
        for k in p:
            if k not in ("key", "low", "high", "scale", "initial"):
                _fail(f"{where}.{k}", p[k], "not a field; allowed key, low, high, scale, initial")
    obj = {"time_history": 1.0} if doc.get("objective") is None else doc["objective"]
    if not isinstance(obj, dict):
        _fail("objective", obj, "a map with statistics, time_history, spectrum (or null: {time_history: 1})")
    for k in obj:
        if k not in ("statistics", "time_history", "spectrum"):
            _fail(f"objective.{k}", obj[k], "statistics, time_history or spectrum")
    stats = {} if obj.get("statistics") is None else obj["statistics"]
    if not isinstance(stats, dict):
        _fail("objective.statistics", stats, "a map NAME: weight (or null: none)")
    weights = {}
    for k, w in stats.items():
        if k not in cm.TOLERANCE_NAMES or k in cm.DIFFERENCES:
            _fail(f"objective.statistics.{k}", w, "a statistic: " + ", ".join(
                n for n in cm.TOLERANCE_NAMES if n not in cm.DIFFERENCES))
        weights[k] = _weight(w, f"objective.statistics.{k}")
    out["objective"] = {"statistics": weights,
                        "time_history": _weight(obj.get("time_history", 0.0), "objective.time_history"),
                        "spectrum": _weight(obj.get("spectrum", 0.0), "objective.spectrum")}
    if not any(weights.values()) and not out["objective"]["time_history"] and not out["objective"]["spectrum"]:
        _fail("objective", obj, "at least one weight above 0 (left out or null: {time_history: 1})")
    opt = {} if doc.get("optimiser") is None else doc["optimiser"]
    if not isinstance(opt, dict):
        _fail("optimiser", opt, "a map {method, max_evaluations} (or null: least_squares, 100)")
    for k in opt:
        if k not in ("method", "max_evaluations"):
            _fail(f"optimiser.{k}", opt[k], "not a field; allowed method, max_evaluations")
    method = opt.get("method", "least_squares")
    if method not in METHODS:
        _fail("optimiser.method", method, "one of " + ", ".join(METHODS))
    n = opt.get("max_evaluations", 100)
    least = 2 + reserved_passes(len(params))
    if isinstance(n, bool) or not isinstance(n, int) or not least <= n <= 100000:
        _fail("optimiser.max_evaluations", n, f"an integer from {least} to 100000: the passes the calibration runs, "
              f"at least the optimiser's first two and the {reserved_passes(len(params))} of the uncertainty at its "
              f"end for {len(params)} parameter(s)")
    out["optimiser"] = {"method": method, "max_evaluations": n}
    check_bounds(out)
    return out


def reserved_passes(n):
    """The passes kept for the uncertainty at the optimum of n parameters: the Jacobian's n + 1 and
    the n one difference step on the other side (its point may be one already run)."""
    return 2 * n + 1


class _OutOfPasses(Exception):
    """The optimiser asked for more passes than optimiser.max_evaluations leaves it."""


def check_bounds(cal):
    """Refuses a parameter's low or high the scene refuses (beyond the field's range, or a scene
    it makes invalid), naming the calibration field: the scene is checked with the overrides and
    each bound in turn, then with every parameter at its initial value, before any pass."""
    from . import check_scene
    params = cal["parameters"]
    try:
        check_scene(cal["scene"], cal["overrides"])
    except SceneError as e:
        raise CalibrationError(f"calibration {cal['path']}: {e}") from None

    def refers_to(e, value):  # the scene's error is about this value of the field
        try:
            return math.isclose(float(e.value), value, rel_tol=1e-9, abs_tol=0.0)
        except (TypeError, ValueError):
            return False

    for i, p in enumerate(params):
        # A field the scene takes text for (a name) also takes a bound, as its text: it is not a
        # number the optimiser can move, though the bounds pass.
        try:
            check_scene(cal["scene"], dict(cal["overrides"], **{p["key"]: "text"}))
        except SceneError:
            pass
        else:
            _fail(f"parameters[{i}].key", p["key"], "a number field of the scene (this one takes text)")
        for bound in ("low", "high"):
            try:
                check_scene(cal["scene"], dict(cal["overrides"], **{p["key"]: p[bound]}))
            except SceneError as e:
                if e.field == p["key"] and refers_to(e, p[bound]):
                    _fail(f"parameters[{i}].{bound}", p[bound], f"the scene field {p['key']}'s {e.allowed}")
                if e.field == p["key"]:
                    _fail(f"parameters[{i}].key", p["key"], f"a number field of the scene ({e})")
                _fail(f"parameters[{i}].{bound}", p[bound], f"a bound the scene takes ({e})")
    start = {p["key"]: p.get("initial", to_values([p], [0.5])[0]) for p in params}
    try:
        check_scene(cal["scene"], dict(cal["overrides"], **start))
    except SceneError as e:
        raise CalibrationError(f"calibration {cal['path']}: parameters at their initial values {start}: {e}") from None


# --------------------------------------------------------------------------------------------
# Parameters on the unit scale, residuals
# --------------------------------------------------------------------------------------------
def to_values(params, u):
    out = []
    for p, x in zip(params, np.clip(u, 0.0, 1.0)):
        lo, hi = float(p["low"]), float(p["high"])
        out.append(lo * (hi / lo) ** x if p.get("scale") == "log" else lo + x * (hi - lo))
    return out


def to_unit(params, values):
    out = []
    for p, v in zip(params, values):
        lo, hi = float(p["low"]), float(p["high"])
        out.append(math.log(v / lo) / math.log(hi / lo) if p.get("scale") == "log" else (v - lo) / (hi - lo))
    return np.array(out)


def residuals(comparison, objective):
    """The residual vector of a comparison: each chosen statistic's relative deviation (absolute
    when the record's value is 0) times its weight; with time_history the filtered force's
    difference over the section in units of the record's std, / sqrt(rows) (its squares sum to the
    mean square); with spectrum the dB differences up to the cutoff, / sqrt(frequencies)."""
    r = []
    for row in comparison.rows:
        w = objective["statistics"].get(row["quantity"])
        if w and row["deviation"] is not None:
            scale = abs(row["record"]) if row["record"] else 1.0
            r.append(w * row["deviation"] / scale)
    s = comparison.series
    inside = s["in_section"].to_numpy() > 0
    for p in comparison.record.force_N:
        if objective["time_history"]:
            rec = s[f"record_force_{p}_filtered_N"].to_numpy()[inside]
            sim = s[f"simulated_force_{p}_filtered_N"].to_numpy()[inside]
            r.extend(objective["time_history"] * (sim - rec) / (np.std(rec) * math.sqrt(len(rec))))
        if objective["spectrum"]:
            t = comparison.spectra[comparison.spectra["pantograph"] == p]
            f = t["frequency_hz"].to_numpy()
            pr, ps = t["record_psd_N2_per_hz"].to_numpy(), t["simulated_psd_N2_per_hz"].to_numpy()
            band = (f > 0) & (f <= min(comparison.settings["cutoff_hz"], comparison.record.bandwidth_hz)) & \
                (pr > 0) & (ps > 0)
            r.extend(objective["spectrum"] * 10 * np.log10(ps[band] / pr[band]) / math.sqrt(band.sum()))
    return np.asarray(r, dtype=float)


def evaluate(cal, keys, values):
    """One evaluation (runs on a Dask worker): the residuals at these parameter values."""
    ov = dict(cal["overrides"])
    ov.update(zip(keys, values))
    try:
        c = cm.compare(cal["scene"], cal["record"], overrides=ov, speed_profile=cal["speed_profile"],
                       cutoff_hz=cal["cutoff"], meta=cal["meta"])
    except RuntimeError as e:  # the watchdog stopped the pass: say at which parameter values
        raise RuntimeError("the pass at %s: %s" % (", ".join("%s = %.6g" % kv for kv in zip(keys, values)), e)) from None
    return {"residuals": residuals(c, cal["objective"]).tolist(),
            "band_hz": min(c.settings["cutoff_hz"], c.record.bandwidth_hz)}


def _file_digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def fingerprint(cal):
    """A digest of everything besides the parameter values that decides an evaluation's residuals:
    the scene's and the record's text (with the record's side metadata), the overrides, speed
    profile, cutoff, objective and which scene fields the parameters are. Evaluations kept under
    one fingerprint are never replayed for a calibration with another."""
    side = cal["meta"]
    if side is None:
        stem = os.path.splitext(cal["record"])[0]
        side = next((stem + e for e in (".yaml", ".yml") if os.path.isfile(stem + e)), None)
    try:
        files = {"scene": _file_digest(cal["scene"]), "record": _file_digest(cal["record"]),
                 "meta": _file_digest(side) if side else None}
    except OSError as e:
        raise CalibrationError(f"calibration file {cal['path']!r}: {e}") from None
    doc = {"files": files, "overrides": cal["overrides"], "speed_profile": cal["speed_profile"],
           "cutoff": cal["cutoff"], "objective": cal["objective"],
           "parameters": [p["key"] for p in cal["parameters"]]}
    return hashlib.sha256(json.dumps(doc, sort_keys=True, default=repr).encode()).hexdigest()[:16]


def _key(context, values):
    return hashlib.sha1(json.dumps([context, [float("%.12g" % v) for v in values]]).encode()).hexdigest()[:16]


class _Evaluator:
    """Evaluations by their parameter values, on the cluster, each kept in DIR/evaluations/."""

    def __init__(self, cal, out, client):
        self.cal, self.client = cal, client
        self.keys = [p["key"] for p in cal["parameters"]]
        self.dir = os.path.join(out, "evaluations")
        self.context = fingerprint(cal)
        os.makedirs(self.dir, exist_ok=True)
        self.count = self.replayed = 0
        # The parameter points this calibration has evaluated: each a pass, run now or by an
        # earlier start on the same DIR (read back), counted against `limit` once.
        self.points = set()
        self.limit = None
        self.best = (math.inf, None)

    def many(self, us):
        values = [to_values(self.cal["parameters"], u) for u in us]
        new = {_key(self.context, v) for v in values} - self.points
        if self.limit is not None and len(self.points) + len(new) > self.limit:
            raise _OutOfPasses()
        self.points |= new
        results, todo = [None] * len(values), []
        for i, v in enumerate(values):
            path = os.path.join(self.dir, _key(self.context, v) + ".json")
            done = None
            if os.path.isfile(path):
                with open(path, encoding="utf-8") as f:
                    done = json.load(f)
            if done is not None and done.get("context") == self.context:
                results[i] = np.array(done["residuals"])
                self.band_hz = done["band_hz"]
                self.replayed += 1
            else:
                todo.append(i)
        futures = [self.client.submit(evaluate, self.cal, self.keys, values[i], pure=False) for i in todo]
        for i, fut in zip(todo, futures):
            r = fut.result()
            self.keep(values[i], r)
            results[i] = np.array(r["residuals"])
            self.band_hz = r["band_hz"]
        self.count += len(values)
        for u, r in zip(us, results):
            cost = 0.5 * float(np.sum(r ** 2))
            if cost < self.best[0]:
                self.best = (cost, np.array(u, dtype=float))
        return results

    def keep(self, values, r):
        """Checks an evaluation's residuals and keeps it in DIR/evaluations/."""
        if not r["residuals"] or not np.all(np.isfinite(r["residuals"])):
            raise CalibrationError(
                f"calibration {self.cal['path']}: objective = {self.cal['objective']!r} gives "
                f"{'no residuals' if not r['residuals'] else 'non-finite residuals'} at "
                f"{dict(zip(self.keys, values))}; allowed an objective the record and the pass can measure")
        write_atomically(os.path.join(self.dir, _key(self.context, values) + ".json"),
                          json.dumps({"context": self.context, "values": dict(zip(self.keys, values)), **r}))

    def jacobian(self, u):
        """Forward differences in the unit scale, stepping inwards at an upper bound; all n + 1
        passes at once on the cluster."""
        n = len(u)
        points = [np.array(u, dtype=float)]
        steps = []
        for i in range(n):
            h = DIFF_STEP if u[i] + DIFF_STEP <= 1.0 else -DIFF_STEP
            x = np.array(u, dtype=float)
            x[i] += h
            points.append(x)
            steps.append(h)
        res = self.many(points)
        return res[0], np.column_stack([(res[i + 1] - res[0]) / steps[i] for i in range(n)])


def uncertainty(params, u, r, jac_u, correlated=1.0):
    """Each parameter's standard uncertainty from the Jacobian at the optimum, cov = s^2 (J^T J)^+
    with s^2 = sum r^2 / (m - n) (the residuals' own scatter), times `correlated`, the number of
    residuals per independent one (a time history sampled at fs and band-limited to B holds
    2 B independent values a second: fs / 2B per one), and which parameters the record
    cannot identify: a parameter with a large share (> 1/2) in a direction of the parameters whose
    singular value is below IDENTIFIABLE_SV of the largest, or whose std exceeds its range."""
    m, n = jac_u.shape
    dof = max(m / correlated - n, 1.0)
    s2 = float(np.sum(r ** 2)) / dof
    sv_u, sv, vt = np.linalg.svd(jac_u, full_matrices=False)
    cov_u = s2 * np.linalg.pinv(jac_u.T @ jac_u)
    values = to_values(params, u)
    out = []
    weak = sv < IDENTIFIABLE_SV * (sv[0] if len(sv) and sv[0] > 0 else 1.0)
    for i, p in enumerate(params):
        lo, hi = float(p["low"]), float(p["high"])
        # d value / d u at the optimum (log scale: value x ln(hi / lo))
        dvdu = values[i] * math.log(hi / lo) if p.get("scale") == "log" else hi - lo
        std = math.sqrt(max(cov_u[i, i], 0.0)) * abs(dvdu)
        share = float(np.sum(vt[weak, i] ** 2)) if weak.any() else 0.0
        reasons = []
        if share > 0.5:
            reasons.append("the residuals hardly change along it (singular value below %g of the largest)" %
                           IDENTIFIABLE_SV)
        if std > hi - lo:
            reasons.append("its uncertainty exceeds its range")
        out.append({"key": p["key"], "value": values[i], "std": std, "identifiable": not reasons,
                    "why_not": "; ".join(reasons) or None, "low": lo, "high": hi})
    return out, {"singular_values": sv.tolist(), "residual_variance": s2, "residuals": m}


def calibrate(path, out, scheduler=None, workers=2, report=True):
    """Runs a calibration file into DIR (resumable); returns the dict of calibration.json.
    Raises CalibrationError (or SceneError) for bad input, with nothing written, and RuntimeError
    naming the parameter values where the watchdog stopped a diverging pass (the evaluations kept
    before it stay in DIR)."""
    from dask.distributed import Client, LocalCluster
    import dask

    for name, v in (("path", path), ("out", out)):
        _check_path(name, v, CalibrationError)
    _check_workers(workers, CalibrationError)
    if scheduler is not None and not isinstance(scheduler, str):
        raise CalibrationError(f"scheduler = {scheduler!r}: allowed None or an address such as tcp://host:8786")
    cal = load_calibration(path)
    out = os.path.abspath(out)
    _check_output_dir(out, CalibrationError)
    params = cal["parameters"]
    # Checked here, before any cluster starts: the record and the cutoff (load_calibration checked the
    # scene at each bound and at the initial values).
    rec = cm.read_record(cal["record"], cal["meta"])
    measurable(cal, rec)
    try:
        cm._cutoff(cal["cutoff"], rec)
    except SceneError as e:
        _fail("cutoff", cal["cutoff"], e.allowed)
    # The initial values (the range's middle unless given), just inside the bounds as the
    # trust-region method needs.
    u0 = np.array([to_unit([p], [p["initial"]])[0] if "initial" in p else 0.5 for p in params])
    u0 = np.clip(u0, 1e-6, 1.0 - 1e-6)
    # The first evaluation here, before a cluster starts or DIR is made (unless DIR keeps it):
    # what only the comparison refuses (the record's section, supports or bandwidth against the
    # scene) is refused with nothing written; the cluster then reads it back.
    v0 = to_values(params, u0)
    kept = os.path.join(out, "evaluations", _key(fingerprint(cal), v0) + ".json")
    first = None
    if not os.path.isfile(kept):
        try:
            first = evaluate(cal, [p["key"] for p in params], v0)
        except SceneError as e:
            raise CalibrationError(f"calibration {path}: {e}") from None
        if not first["residuals"] or not np.all(np.isfinite(first["residuals"])):
            first = None  # refused by the evaluator with its message, as any evaluation
    own = None
    if scheduler:
        try:
            client = Client(scheduler, timeout=10)
        except (OSError, ValueError, TypeError) as e:
            raise CalibrationError(f"scheduler = {scheduler!r}: cannot be reached ({e}); allowed the address "
                                   "of a running dask-scheduler, e.g. tcp://host:8786") from None
    else:
        with dask.config.set({"distributed.worker.profile.enabled": False}):
            own = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(own)
    try:
        _make_output_dir(out, "evaluations", CalibrationError)
        ev = _Evaluator(cal, out, client)
        if first is not None:
            ev.keep(v0, first)
        budget = cal["optimiser"]["max_evaluations"]
        # Every pass counts against the budget, the Jacobian's too; the optimiser may use all but
        # those the uncertainty at its end needs, and stops cleanly at its share.
        ev.limit = budget - reserved_passes(len(params))
        r0 = ev.many([u0])[0]
        try:
            if cal["optimiser"]["method"] == "least_squares":
                res = optimize.least_squares(lambda u: ev.many([u])[0], u0, jac=lambda u: ev.jacobian(u)[1],
                                             bounds=(np.zeros(len(u0)), np.ones(len(u0))), method="trf",
                                             max_nfev=budget, x_scale=1.0)
                u = res.x
            else:
                method = cal["optimiser"]["method"].split(":", 1)[1]
                res = optimize.minimize(lambda u: 0.5 * float(np.sum(ev.many([u])[0] ** 2)), u0, method=method,
                                        bounds=[(0.0, 1.0)] * len(u0), options={"maxfev": budget})
                u = np.clip(res.x, 0.0, 1.0)
            converged, message = bool(res.success), str(res.message)
        except _OutOfPasses:
            # The best point evaluated so far.
            u, converged = ev.best[1], False
            message = (f"stopped at optimiser.max_evaluations = {budget} passes ({len(ev.points)} run by the "
                       f"optimiser, {reserved_passes(len(params))} kept for the uncertainty at its end)")
        ev.limit = budget
        r, jac = ev.jacobian(u)
        # The linear model checked on the other side of the optimum, one difference step away.
        steps = [-DIFF_STEP if u[i] - DIFF_STEP >= 0.0 else 2 * DIFF_STEP for i in range(len(u))]
        others = ev.many([u + np.eye(len(u))[i] * steps[i] for i in range(len(u))])
        ratio = 0.0
        for i, ri in enumerate(others):
            change = np.linalg.norm(jac[:, i] * steps[i])
            miss = np.linalg.norm(ri - (r + jac[:, i] * steps[i]))
            ratio = max(ratio, miss / change if change > 0 else (0.0 if miss == 0 else math.inf))
        correlated = max(1.0, rec.sample_rate_hz / (2.0 * ev.band_hz)) if cal["objective"]["time_history"] else 1.0
        table, info = uncertainty(params, u, r, jac, correlated)
        info["residuals_per_independent_one"] = correlated
        info["linearity_ratio"] = ratio if math.isfinite(ratio) else None
        info["uncertainty_available"] = bool(ratio <= LINEAR_RATIO)
        if not info["uncertainty_available"]:
            for p in table:
                p.update(std=None, identifiable=None,
                         why_not="uncertainty not available: the objective is rough at the difference step "
                                 "(a finer numerics.preset makes it smooth)")
        result = {"calibration": os.path.abspath(path), "method": cal["optimiser"]["method"],
                  "converged": converged, "message": message, "max_evaluations": budget,
                  "passes": len(ev.points), "evaluations": ev.count, "replayed": ev.replayed,
                  "cost_before": 0.5 * float(np.sum(r0 ** 2)), "cost_after": 0.5 * float(np.sum(r ** 2)),
                  "rms_residual_before": float(np.sqrt(np.mean(r0 ** 2))),
                  "rms_residual_after": float(np.sqrt(np.mean(r ** 2))),
                  "parameters": table, **info}
    finally:
        client.close()
        if own is not None:
            own.close()
    snippet = {}
    for p in table:
        node = snippet
        parts = p["key"].split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = float("%.6g" % p["value"])
    write_atomically(os.path.join(out, "calibrated.yaml"),
                      "# calibrated against %s (rms residual %.4g, was %.4g)%s\n" % (
                          cal["record"], result["rms_residual_after"], result["rms_residual_before"],
                          "" if result["converged"] else "; NOT CONVERGED: " + result["message"])
                      + yaml.safe_dump(snippet, sort_keys=False))
    write_atomically(os.path.join(out, "calibration.json"), json.dumps(result, indent=2, allow_nan=False) + "\n")
    if report:
        for name, values in (("before", to_values(params, u0)), ("after", [p["value"] for p in table])):
            ov = dict(cal["overrides"])
            ov.update(zip([p["key"] for p in params], values))
            cm.compare(cal["scene"], rec, overrides=ov, speed_profile=cal["speed_profile"],
                       cutoff_hz=cal["cutoff"]).write(os.path.join(out, name), pass_files=False)
    return result


def main():
    import argparse
    import sys
    ap = argparse.ArgumentParser(description="calibrate: scene parameters from a measured record")
    ap.add_argument("calibration", help="the calibration file (YAML)")
    ap.add_argument("--out", required=True, help="output directory (resumes the evaluations found there)")
    ap.add_argument("--workers", type=int, default=2, help="local Dask workers (default 2; ignored with --scheduler)")
    ap.add_argument("--scheduler", help="address of a running dask-scheduler, e.g. tcp://host:8786")
    ap.add_argument("--no-report", action="store_true", help="no before/ and after/ comparisons")
    a = ap.parse_args()
    if not 1 <= a.workers <= 1024:
        ap.error(f"--workers {a.workers}: allowed 1 to 1024")
    try:
        result = calibrate(a.calibration, a.out, a.scheduler, a.workers, not a.no_report)
    except (CalibrationError, SceneError) as e:
        sys.stderr.write(f"calibrate: {e}\n")
        return 2
    except RuntimeError as e:  # a pass diverged (the evaluations before it are kept in --out)
        sys.stderr.write(f"calibrate: {e}\n")
        return 3
    if not result["converged"]:
        print("NOT CONVERGED: %s (the values below are where the optimiser stopped)" % result["message"])
    if not result["uncertainty_available"]:
        print("UNCERTAINTY NOT AVAILABLE: the objective is rough at the difference step (the other side of "
              "the optimum departs from the linear model by %s of the change); use a finer numerics.preset" % (
                  "%.2g" % result["linearity_ratio"] if result["linearity_ratio"] is not None else "all"))
    for p in result["parameters"]:
        if p["std"] is None:
            print("%-32s %.6g" % (p["key"], p["value"]))
        else:
            print("%-32s %.6g +- %.2g%s" % (p["key"], p["value"], p["std"],
                                           "" if p["identifiable"] else "  NOT IDENTIFIABLE: " + p["why_not"]))
    print("rms residual %.4g (was %.4g), %d passes of at most %d (max_evaluations), %d evaluations (%d read "
          "back); wrote %s" % (result["rms_residual_after"], result["rms_residual_before"], result["passes"],
                               result["max_evaluations"], result["evaluations"], result["replayed"], a.out))
    return 0
