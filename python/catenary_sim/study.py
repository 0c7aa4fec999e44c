"""Studies: many passes of one scene with parameters varied, run on Dask distributed.

    catenary_sim_study STUDY.yaml --out DIR [--workers 2 | --scheduler tcp://host:8786]
    from catenary_sim.study import run_study; table = run_study("STUDY.yaml", "DIR")

A study file (YAML; paths relative to it):

    name: uplift_and_speed
    scene: ../config/reference_55m.yaml
    overrides: {numerics.preset: balanced}          # applied to every case
    sampling: grid                                  # grid | random | lhs | sobol | saltelli
    samples: 64                                     # random, lhs, sobol, saltelli (base samples N)
    seed: 1                                         # random, lhs, sobol, saltelli
    parameters:
      - key: pantographs.0.static_uplift            # any scene field, as simulate_pass --set
        values: [80, 100, 120]                      # grid; any YAML value: a list for a list field,
                                                    # null for the scene's default (a rule's choice)
        labels: [low, nominal, high]                # optional, grid: names in results.csv and plots
      - key: train.speed_kmh
        distribution: {type: uniform, low: 200, high: 300}      # random, lhs, sobol, saltelli
        # {type: normal, mean: 0, std: 0.01}, {type: truncated_normal, mean, std, low, high},
        # {type: integers, low: 0, high: 1000000} (e.g. the seed of a random line)
    outputs: [pantographs.0.std_force_N, pantographs.0.max_force_N]   # paths into stats.json
    bootstrap: 200                                  # saltelli: resamples for the confidence intervals
    report: false                                   # true: each case's pass report (scripts/pass_report)
                                                    # in DIR/cases/NNNNNN/, linked from results.csv and
                                                    # DIR/index.html

The scene with the overrides, each parameter's key and each output are checked before any case
runs (a key or output the scene lacks would fail every case). Each case is written atomically to
DIR/cases/NNNNNN.json when it finishes; a study started again on the same DIR resumes where it
stopped (the plan must be the same); a failed case is recorded with its message (its outputs null)
and the others go on. The table DIR/results.csv (pandas.read_csv) has one row per
case: its parameters, the outputs, status and message. Plots: DIR/*.png. With sampling: saltelli,
DIR/sensitivity.json holds first-order and total Sobol indices with bootstrap intervals.
A thin skin: the passes are the core's (catenary_sim.run_pass); no physics here.
"""
import fcntl
import itertools
import json
import math
import os
import time

import numpy as np
import yaml

from . import SceneError
from ._files import write_atomically

SAMPLINGS = ("grid", "random", "lhs", "sobol", "saltelli")
DISTRIBUTIONS = ("uniform", "normal", "truncated_normal", "integers")

# A study file is read whole; beyond this it is refused (a study file is a page of YAML; a grid of
# 100,000 values is about 1 MiB).
MAX_STUDY_BYTES = 64 << 20
# The plan is held in memory (a dict per case, about 1 kB with its record) and written to
# plan.json; 100,000 passes are days of a cluster's time. Counted before the cases are made.
MAX_CASES = 100_000
# scipy's Sobol sequence has at most 21,201 dimensions (saltelli draws 2 per parameter).
MAX_PARAMETERS = 1000


class StudyError(ValueError):
    """A study file that cannot be run: names the field, the value and what is allowed."""


# What a number written as text is refused with, in study and calibration files alike.
TEXT_NUMBER_HINT = "not text (YAML 1.1 reads an exponent without a sign, e.g. 1.0e308, as text: write 1.0e+308)"


def _fail(field, value, allowed):
    raise StudyError(f"study field '{field}' = {value!r}: {allowed}")


# --------------------------------------------------------------------------------------------
# The study file
# --------------------------------------------------------------------------------------------
class _StrictLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """YAML as safe_load reads it (libyaml's parser where present: a 100,000-value grid in seconds),
    but a key given twice in one map is refused (not last-wins) and aliases are refused (a
    self-referencing or exponentially expanding one cannot be a plan). Its refusals are `error`s
    naming the file as `what` (a calibration file's loader is this one with its own)."""

    error, what = StudyError, "study file"

    @classmethod
    def load(cls, text, name):
        """The one document of `text`; `name` (the file) for the messages."""
        loader = cls(text)
        loader.name = name
        try:
            return loader.get_single_data()
        finally:
            loader.dispose()

    def get_single_data(self):
        node = self.get_single_node()
        if node is None:
            return None
        # An alias is the same node met twice in the graph (the parser shares it): looked for
        # without recursion, so a self-reference ends here too.
        seen, stack = set(), [(node, 0)]
        while stack:
            n, depth = stack.pop()
            if depth > 64:  # a plan is a few levels deep; thousands overflow Python's recursion
                raise self.error(f"{self.what} '{self.name}' line {n.start_mark.line + 1}: nested more than 64 levels "
                                 f"deep; a {self.what} is a few levels of maps and lists")
            if id(n) in seen:
                raise self.error(f"{self.what} '{self.name}' line {n.start_mark.line + 1}: this value is used again "
                                 f"through an alias (*name): aliases and anchors are not allowed in a {self.what}; "
                                 "write the value out")
            seen.add(id(n))
            if isinstance(n, yaml.SequenceNode):
                stack.extend((v, depth + 1) for v in n.value)
            elif isinstance(n, yaml.MappingNode):
                for k, v in n.value:
                    stack.extend(((k, depth + 1), (v, depth + 1)))
        return self.construct_document(node)

    def construct_mapping(self, node, deep=False):
        seen = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            try:
                hash(key)
            except TypeError:
                raise self.error(f"{self.what} '{self.name}' line {key_node.start_mark.line + 1}: a key that is a "
                                 "list or map; allowed text or number keys") from None
            if key in seen:
                raise self.error(f"{self.what} '{self.name}' line {key_node.start_mark.line + 1}: key '{key}' is given "
                                 f"twice in one map (first on line {seen[key] + 1}); allowed each key once")
            seen[key] = key_node.start_mark.line
        return super().construct_mapping(node, deep)


def _check_path(name, value, error=StudyError):
    """A path argument: refused by its name unless text or os.PathLike (as `error`: a calibration
    refuses its arguments alike)."""
    if not isinstance(value, (str, os.PathLike)):
        raise error(f"{name} = {value!r}: allowed a file path (str or os.PathLike)")


def _check_output_dir(out, error=StudyError):
    """An output directory (made if absent): refused by `error` if it is something else, or if the
    nearest part of its path that exists cannot take new entries, before any case runs."""
    if os.path.lexists(out) and not os.path.isdir(out):
        raise error(f"--out {out}: exists and is not a directory; allowed a directory (made if absent)")
    there = os.path.abspath(out)
    while not os.path.lexists(there):
        there = os.path.dirname(there)
    if not os.path.isdir(there) or not os.access(there, os.W_OK | os.X_OK):
        raise error(f"--out {out}: cannot be written ('{there}' " + ("is not a directory" if not os.path.isdir(there)
                    else "takes no new entries") + "); allowed a directory that can be made and written")


def _make_output_dir(out, sub, error=StudyError):
    """Makes out/sub and what of its path is missing; returns the directories made, deepest first
    (for _unmake). An OSError is `error` naming --out, with nothing made left behind."""
    made, d = [], os.path.abspath(os.path.join(out, sub))
    while not os.path.lexists(d):
        made.append(d)
        d = os.path.dirname(d)
    try:
        os.makedirs(os.path.join(out, sub), exist_ok=True)
    except OSError as e:
        _unmake(made)
        raise _unwritable(out, e, error) from None
    return made


def _unwritable(out, e, error=StudyError):
    """`error` for an OSError met writing into --out."""
    return error(f"--out {out}: cannot be written ({e.strerror or e}); allowed a directory that can be made and written")


def _unmake(made):
    """Takes away directories _make_output_dir made, if they are still empty (nothing of anyone
    else's goes)."""
    for d in made:
        try:
            os.rmdir(d)
        except OSError:
            pass


def _check_workers(workers, error=StudyError):
    """The local cluster's worker count: an integer from 1 to 1024 (True is not 1 worker)."""
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= 1024:
        raise error(f"workers = {workers!r}: allowed an integer from 1 to 1024")


def load_study(path):
    """Reads and checks a study file; returns a dict with absolute paths. Raises StudyError."""
    _check_path("path", path)
    if os.path.isdir(path):
        raise StudyError(f"study file '{path}' is a directory; expected a YAML file")
    try:
        with open(path, "rb") as f:
            raw = f.read(MAX_STUDY_BYTES + 1)
    except OSError as e:
        raise StudyError(f"study file '{path}' cannot be read ({e.strerror or e}); allowed a readable YAML "
                         "file") from None
    if len(raw) > MAX_STUDY_BYTES:
        raise StudyError(f"study file '{path}' is larger than {MAX_STUDY_BYTES >> 20} MiB: allowed at most "
                         f"{MAX_STUDY_BYTES >> 20} MiB (a study is a page of YAML)")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise StudyError(f"study file '{path}': not UTF-8 text ({e.reason} at byte {e.start})") from None
    try:
        doc = _StrictLoader.load(text, path)
    except yaml.YAMLError as e:
        raise StudyError(f"study file '{path}': not valid YAML: {e}") from None
    except RecursionError:
        raise StudyError(f"study file '{path}': nested too deeply") from None
    if not isinstance(doc, dict):
        raise StudyError(f"study file '{path}': expected a map of fields (name, scene, parameters, ...)")
    known = {"name", "scene", "overrides", "sampling", "samples", "seed", "parameters", "outputs", "bootstrap", "report"}
    for k in doc:
        if k not in known:
            _fail(k, doc[k], f"unknown field; allowed: {', '.join(sorted(known))}")
    base = os.path.dirname(os.path.abspath(path))
    s = {"name": str(doc.get("name", os.path.splitext(os.path.basename(path))[0]))}
    scene = doc.get("scene")
    if not isinstance(scene, str):
        _fail("scene", scene, "required: the scene file, relative to the study file")
    s["scene"] = scene if os.path.isabs(scene) else os.path.normpath(os.path.join(base, scene))
    if not os.path.isfile(s["scene"]):
        _fail("scene", scene, f"a scene file; '{s['scene']}' " + ("is a directory" if os.path.isdir(s["scene"]) else "does not exist"))
    ov = {} if doc.get("overrides") is None else doc["overrides"]  # left out or null: none
    if not isinstance(ov, dict):  # a list, 0 or false is not read as no overrides
        _fail("overrides", ov, "a map {dotted.key: value} (or null: none)")
    for key, value in ov.items():  # named here, not by the whole file's check below
        try:
            json.dumps(value, allow_nan=False)
        except (TypeError, ValueError):
            _fail(f"overrides.{key}", value, "a finite number, text, true/false, null, a list or a map (each case's "
                  "overrides are written to plan.json, which holds no NaN, infinity or other types)")
    s["overrides"] = ov
    s["sampling"] = doc.get("sampling", "grid")
    if s["sampling"] not in SAMPLINGS:
        _fail("sampling", s["sampling"], f"one of {', '.join(SAMPLINGS)}")
    params = doc.get("parameters")
    if not isinstance(params, list) or not params:
        _fail("parameters", params, "a non-empty list of {key, values} or {key, distribution}")
    if len(params) > MAX_PARAMETERS:
        _fail("parameters", f"a list of {len(params)}", f"at most {MAX_PARAMETERS} parameters")
    s["parameters"] = []
    seen = set()
    for i, p in enumerate(params):
        f = f"parameters[{i}]"
        if not isinstance(p, dict) or not isinstance(p.get("key"), str) or not p["key"]:
            _fail(f + ".key", p, "a scene field as a dotted key, e.g. pantographs.0.static_uplift")
        for k in p:
            if k not in ("key", "values", "labels", "distribution"):
                _fail(f"{f}.{k}", p[k], "unknown field; allowed: key, values, labels, distribution")
        if p["key"] in seen:
            _fail(f + ".key", p["key"], "each parameter once")
        seen.add(p["key"])
        if s["sampling"] == "grid":
            if "distribution" in p:  # it would be ignored: a grid's cases are its values
                _fail(f + ".distribution", p["distribution"], "only with sampling: random, lhs, sobol or saltelli; "
                      "a grid parameter has values")
            v = p.get("values")
            if not isinstance(v, list) or not v:
                _fail(f + ".values", v, "a non-empty list of values (sampling: grid)")
            labels = p.get("labels")
            if labels is None:
                labels = [_label(x) for x in v]
            elif not isinstance(labels, list) or len(labels) != len(v) or not all(isinstance(x, (str, int, float)) for x in labels):
                _fail(f + ".labels", labels, f"a list of {len(v)} names, one per value")
            if len(set(map(str, labels))) != len(labels):
                _fail(f + ".labels", labels, "distinct names (give labels for values that print alike)")
            if not all(_finite(x) for x in v):
                _fail(f + ".values", v, "finite numbers (NaN and inf cannot be a scene's value), text, true/false, "
                      "null, lists and maps")
            s["parameters"].append({"key": p["key"], "values": v, "labels": labels})
        elif "labels" in p:
            _fail(f + ".labels", p["labels"], "only with sampling: grid")
        elif "values" in p:
            _fail(f + ".values", p["values"], f"only with sampling: grid; a parameter of sampling: {s['sampling']} "
                  "has a distribution")
        else:
            s["parameters"].append({"key": p["key"], "distribution": _check_distribution(p.get("distribution"), f)})
    if s["sampling"] == "grid" and "samples" in doc:
        _fail("samples", doc["samples"], "only with sampling: random, lhs, sobol or saltelli; a grid's cases are "
              "the combinations of its values")
    if s["sampling"] != "grid":
        n = doc.get("samples")
        if not isinstance(n, int) or isinstance(n, bool) or not 1 <= n <= 1_000_000:
            _fail("samples", n, "a whole number of samples in [1, 1000000]")
        s["samples"] = n
    if s["sampling"] == "grid" and "seed" in doc:  # it would be ignored: a grid draws nothing
        _fail("seed", doc["seed"], "only with sampling: random, lhs, sobol or saltelli; a grid's cases are "
              "the combinations of its values and draw nothing")
    seed = doc.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        _fail("seed", seed, "a whole number >= 0")
    s["seed"] = seed
    outs = doc.get("outputs")
    if not isinstance(outs, list) or not outs or not all(isinstance(o, str) and o for o in outs):
        _fail("outputs", outs, "a non-empty list of paths into stats.json, e.g. pantographs.0.std_force_N")
    s["outputs"] = outs
    if s["sampling"] != "saltelli" and "bootstrap" in doc:  # it would be ignored: only Sobol indices have intervals
        _fail("bootstrap", doc["bootstrap"], "only with sampling: saltelli (resamples for the Sobol indices' "
              f"intervals); sampling: {s['sampling']} computes no indices")
    b = doc.get("bootstrap", 200)
    if not isinstance(b, int) or isinstance(b, bool) or not 0 <= b <= 100_000:
        _fail("bootstrap", b, "a whole number of resamples in [0, 100000]")
    s["bootstrap"] = b
    report = doc.get("report", False)
    if not isinstance(report, bool):
        _fail("report", report, "true or false (true: a pass report per case)")
    s["report"] = report
    n = case_count(s)
    if n > MAX_CASES:
        field = "parameters" if s["sampling"] == "grid" else "samples"
        how = (" x ".join(str(len(p["values"])) for p in s["parameters"]) + " grid values" if s["sampling"] == "grid"
               else f"{s['samples']} samples" + (f" x ({len(s['parameters'])} parameters + 2)"
                                                 if s["sampling"] == "saltelli" else ""))
        _fail(field, f"{how} = {n} cases", f"at most {MAX_CASES} cases in one study (split it, or sample)")
    try:
        json.dumps(s, allow_nan=False)
    except (TypeError, ValueError) as e:  # a date, a set, inf in a value: not writable to plan.json
        raise StudyError(f"study file '{path}': a value that cannot be written to plan.json ({e}); allowed "
                         "numbers, text, true/false, null, lists and maps") from None
    return s


def _finite(x):
    """False for a NaN or an infinity anywhere in a grid value (lists and maps looked into)."""
    if isinstance(x, float):
        return math.isfinite(x)
    if isinstance(x, list):
        return all(_finite(y) for y in x)
    if isinstance(x, dict):
        return all(_finite(y) for y in x.values())
    return True


def case_count(study):
    """The number of cases of a checked study, known before they are made."""
    if study["sampling"] == "grid":
        return math.prod(len(p["values"]) for p in study["parameters"])
    return study["samples"] * (len(study["parameters"]) + 2 if study["sampling"] == "saltelli" else 1)


def _label(value):
    """A grid value as results.csv and the plots show it: numbers as they are, null as the scene's
    default, anything else (a list) as its YAML flow text."""
    if value is None:
        return "default"
    if isinstance(value, (int, float, str)) and not isinstance(value, bool):
        return value
    return yaml.safe_dump(value, default_flow_style=True, width=1 << 20).strip()


def _check_distribution(d, f):
    f = f + ".distribution"
    if not isinstance(d, dict) or d.get("type") not in DISTRIBUTIONS:
        _fail(f + ".type", (d or {}).get("type") if isinstance(d, dict) else d, f"one of {', '.join(DISTRIBUTIONS)}")
    need = {"uniform": ("low", "high"), "normal": ("mean", "std"), "truncated_normal": ("mean", "std", "low", "high"),
            "integers": ("low", "high")}[d["type"]]
    for k in d:
        if k != "type" and k not in need:
            _fail(f"{f}.{k}", d[k], f"not a field of a {d['type']} distribution ({', '.join(need)})")
    out = {"type": d["type"]}
    for k in need:
        v = d.get(k)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            _fail(f"{f}.{k}", v, "a finite number" + (", " + TEXT_NUMBER_HINT if isinstance(v, str) else ""))
        if d["type"] == "integers" and not float(v).is_integer():  # drawn from floor(low) on: below low
            _fail(f"{f}.{k}", v, "a whole number (an integers distribution draws low, low + 1, ..., high - 1)")
        out[k] = float(v)
    if "std" in out and not out["std"] > 0:
        _fail(f + ".std", out["std"], "> 0")
    if "low" in out and not out["low"] < out["high"]:
        _fail(f + ".high", out["high"], f"> low ({out['low']})")
    if "low" in out and not math.isfinite(out["high"] - out["low"]):  # the samples would be inf
        _fail(f + ".high", out["high"], f"a number whose distance from low ({out['low']}) is finite: high - low "
              "overflows a double (about 1.8e+308)")
    if d["type"] == "normal" and not math.isfinite(abs(out["mean"]) + 8 * out["std"]):  # draws reach 7 std
        _fail(f + ".std", out["std"], f"a std whose 8 std from the mean ({out['mean']}) are finite (a double's "
              "largest is about 1.8e+308)")
    return out


def _ppf(dist, u):
    """Maps uniform samples u in (0, 1) to the distribution (inverse CDF)."""
    from scipy import stats
    u = np.clip(np.asarray(u, dtype=float), 1e-12, 1 - 1e-12)
    if dist["type"] == "uniform":
        return dist["low"] + u * (dist["high"] - dist["low"])
    if dist["type"] == "integers":  # whole numbers low..high-1, equally likely (e.g. seeds of random lines)
        return np.floor(dist["low"] + u * (dist["high"] - dist["low"]))
    if dist["type"] == "normal":
        return stats.norm.ppf(u, loc=dist["mean"], scale=dist["std"])
    a = (dist["low"] - dist["mean"]) / dist["std"]
    b = (dist["high"] - dist["mean"]) / dist["std"]
    return stats.truncnorm.ppf(u, a, b, loc=dist["mean"], scale=dist["std"])


# --------------------------------------------------------------------------------------------
# The plan: one override dict per case
# --------------------------------------------------------------------------------------------
def make_cases(study):
    """The cases of a study, in order: a list of {key: value} (plain floats or grid values)."""
    params = study["parameters"]
    keys = [p["key"] for p in params]
    kind = study["sampling"]
    if kind == "grid":
        return [dict(zip(keys, combo)) for combo in itertools.product(*[p["values"] for p in params])]
    from scipy.stats import qmc
    d, n, seed = len(params), study["samples"], study["seed"]
    if kind == "random":
        u = np.random.default_rng(seed).random((n, d))
    elif kind == "lhs":
        u = qmc.LatinHypercube(d=d, seed=seed).random(n)
    elif kind == "sobol":
        u = qmc.Sobol(d=d, scramble=True, seed=seed).random(n)
    else:  # saltelli: A, B from one 2d-dimensional Sobol sequence, then AB_i (Saltelli 2010)
        ab = qmc.Sobol(d=2 * d, scramble=True, seed=seed).random(n)
        a, b = ab[:, :d], ab[:, d:]
        blocks = [a, b] + [np.where(np.arange(d) == i, b, a) for i in range(d)]
        u = np.vstack(blocks)
    values = np.column_stack([_ppf(p["distribution"], u[:, j]) for j, p in enumerate(params)])
    ints = [p["distribution"]["type"] == "integers" for p in params]
    return [{k: (int(values[i, j]) if ints[j] else float(values[i, j])) for j, k in enumerate(keys)}
            for i in range(values.shape[0])]


def _index_of(values, v):
    for j, x in enumerate(values):
        if json.dumps(x) == json.dumps(v):
            return j
    raise StudyError(f"case value {v!r} is not among the grid's values")


def _node(stats, path, before_pass=False):
    """The value at `path` of stats.json; KeyError naming the part that is not there. With
    before_pass, `stats` is a pass's before it runs (the scene's pantographs and wires, nulls where
    numbers come): a list still empty (the steady arms, the droppers, the events) or a null is
    filled by the pass, and the path is not judged below it (None)."""
    node = stats
    for part in path.split("."):
        if before_pass and (node is None or (isinstance(node, list) and not node)):
            return None
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise KeyError(f"output '{path}': '{part}' is not an index of a list of {len(node)}")
            node = node[int(part)]
        elif isinstance(node, dict) and part in node:
            node = node[part]
        else:
            raise KeyError(f"output '{path}': no field '{part}' in stats.json")
    return node


def _output(stats, path):
    node = _node(stats, path)
    if node is None:
        return float("nan")
    if isinstance(node, bool) or not isinstance(node, (int, float)):
        raise KeyError(f"output '{path}': not a number ({node!r})")
    return float(node)


def check_study_against_scene(study, cases=None):
    """What the scene decides, before any case runs. The scene with the study's overrides must be
    valid, each parameter a field of it, each case's values ones it reads (`cases`: make_cases's,
    made here if not given) and each output a number of its stats.json. What only the model's
    build or the pass refuses is one case's failure. Raises StudyError."""
    import catenary_sim as cs
    try:
        cs.check_scene(study["scene"], overrides=study["overrides"])
    except SceneError as e:
        raise StudyError(f"study fields 'scene' and 'overrides': the scene they give is refused: {e}") from None
    # Every case's values as the scene reads them (a millisecond a case): a value no field allows
    # would only fail its case after the cases before it ran (hours, on a large study). What only
    # the model's build finds (a dt above the stability limit, a slack bridle) still fails its case.
    keys = [p["key"] for p in study["parameters"]]
    for c, case in enumerate(make_cases(study) if cases is None else cases):
        try:
            cs.check_scene(study["scene"], overrides={**study["overrides"], **case})
        except SceneError as e:
            i = _parameter_of(e, keys)
            p = study["parameters"][i] if i is not None else None
            if p is not None and e.value == "(unknown field)":
                raise StudyError(f"study field 'parameters[{i}].key' = '{p['key']}': no such scene field "
                                 f"({e}); allowed the dotted key of a field, as docs/scene_reference.md lists") from None
            if p is None:  # refused for another field (a check across fields): the values together
                field, hint = "parameters", "choose values that the scene takes together"
            elif "values" in p:
                field = f"parameters[{i}].values[{_index_of(p['values'], case[p['key']])}]"
                hint = "leave it out of the values"
            else:
                field = f"parameters[{i}].distribution"
                hint = "keep the distribution inside what the field allows (e.g. a truncated_normal's low and high)"
            given = ", ".join(f"{k} = {_label(v)}" for k, v in case.items())
            raise StudyError(f"study field '{field}': case {c} ({given}) is refused by the scene: {e}; {hint}") from None
    stats = cs.Simulation(study["scene"], overrides=study["overrides"]).statistics(0.0)
    for j, o in enumerate(study["outputs"]):
        try:
            node = _node(stats, o, before_pass=True)
            why = "" if node is None or (isinstance(node, (int, float)) and not isinstance(node, bool)) else \
                f"not a number ({'a group of fields' if isinstance(node, (dict, list)) else repr(node)})"
        except KeyError as e:
            why = str(e).strip("'\"")
        if why:
            raise StudyError(f"study field 'outputs[{j}]' = '{o}': {why}; allowed a number of the pass's stats.json, "
                             "e.g. pantographs.0.std_force_N")


def _parameter_of(error, keys):
    """The index of the study parameter a scene's refusal names (its dotted key as the scene's
    field, `pantographs.0.x` as `pantographs[0].x`), or None."""
    field = getattr(error, "field", None) or ""
    for i, key in enumerate(keys):
        dotted = ".".join(f"[{part}]" if part.isdigit() else part for part in key.split(".")).replace(".[", "[")
        if field == dotted or field.startswith(dotted + ".") or field.startswith(dotted + "["):
            return i
    return None


def _pass_report_script():
    here = os.path.dirname(os.path.abspath(__file__))
    # the sources (devel space: the package is loaded from python/catenary_sim), or an install
    # (PREFIX/lib/python3/dist-packages/catenary_sim -> PREFIX/share/catenary_sim/scripts)
    for d in (os.path.join(here, "..", "..", "scripts"),
              os.path.join(here, "..", "..", "..", "..", "share", "catenary_sim", "scripts")):
        p = os.path.normpath(os.path.join(d, "pass_report"))
        if os.path.isfile(p):
            return p
    raise RuntimeError("scripts/pass_report not found beside the catenary_sim package")


def run_case(scene, overrides, case, outputs, report_dir=None):
    """One pass (runs on a Dask worker). Returns the case's record; never raises. With report_dir,
    the pass's files and its report (scripts/pass_report) are written there before the record."""
    import catenary_sim as cs
    start = time.perf_counter()
    record = {"parameters": case, "status": "ok", "message": "", "outputs": {}}
    try:
        if report_dir is None:
            stats, _ = cs.run_pass(scene, overrides={**overrides, **case}, sample_rate=0)
        else:
            import subprocess
            import sys
            sim = cs.Simulation(scene, overrides={**overrides, **case})
            sim.run()
            stats = sim.statistics(time.perf_counter() - start)
            sim.write_files(report_dir, time.perf_counter() - start)
            r = subprocess.run([sys.executable, _pass_report_script(), report_dir, "--quiet"], capture_output=True,
                               text=True, timeout=600)
            if r.returncode != 0:
                raise RuntimeError(f"pass report of the case failed: {r.stderr.strip() or r.returncode}")
            record["report"] = os.path.join(report_dir, "report.html")
        record["outputs"] = {o: _output(stats, o) for o in outputs}
    except (SceneError, ValueError, RuntimeError, KeyError) as e:
        record["status"] = "failed"
        record["message"] = str(e).strip("'\"")
        record["outputs"] = {o: float("nan") for o in outputs}
    record["wall_time_s"] = time.perf_counter() - start
    return record


# --------------------------------------------------------------------------------------------
# Files: whole or not at all
# --------------------------------------------------------------------------------------------
def _case_path(out, i):
    return os.path.join(out, "cases", f"{i:06d}.json")


def _read_case(out, i, n_outputs, warn=False):
    """A case's record, or None when it is missing or damaged (emptied, cut, not a record): such
    a case is run again, with a word when it was there but unreadable."""
    path = _case_path(out, i)
    if not os.path.exists(path):
        return None
    try:
        with open(path, encoding="utf-8") as f:
            r = json.load(f)
        ok = (isinstance(r, dict) and isinstance(r.get("parameters"), dict) and isinstance(r.get("outputs"), dict)
              and len(r["outputs"]) == n_outputs and r.get("status") in ("ok", "failed")
              and isinstance(r.get("message"), str) and isinstance(r.get("wall_time_s"), (int, float)))
        why = "" if ok else "not a case record (parameters, outputs, status, message, wall_time_s)"
    except (ValueError, OSError) as e:
        ok, why = False, str(e)
    if ok:
        r["outputs"] = {k: math.nan if v is None else v for k, v in r["outputs"].items()}
        return r
    if warn:
        print(f"catenary_sim_study: case file '{path}' is damaged ({why}); the case runs again", flush=True)
    return None


def _plan_difference(old, new):
    """Says which part of two plans differs, for the refusal message."""
    new = json.loads(json.dumps(new))
    if not isinstance(old, dict) or not isinstance(old.get("study"), dict):
        return "its plan.json is not a plan"
    for k in sorted(set(old["study"]) | set(new["study"])):
        if old["study"].get(k) != new["study"].get(k):
            return f"the study field '{k}' differs"
    if len(old.get("cases") or []) != len(new["cases"]):
        return f"{len(old.get('cases') or [])} cases against {len(new['cases'])}"
    return "the cases differ"


def _report_dir(out, i):
    # absolute: the workers of a cluster write it too (a shared file system, as for the scene)
    return os.path.join(os.path.abspath(out), "cases", f"{i:06d}")


# --------------------------------------------------------------------------------------------
# Running
# --------------------------------------------------------------------------------------------
def run_study(study_path, out, scheduler=None, workers=2, progress=True, plots=True):
    """Runs (or resumes) a study into `out`; returns the results table (pandas.DataFrame)."""
    from dask.distributed import Client

    _check_path("study_path", study_path)
    _check_path("out", out)
    _check_output_dir(out)
    study = load_study(study_path)
    _check_workers(workers)
    cases = make_cases(study)
    check_study_against_scene(study, cases)
    # The scheduler is reached before anything is written: a refused address leaves no DIR.
    remote = None
    if scheduler:
        try:
            remote = Client(scheduler, timeout=10)
        except Exception as e:  # a bad address or no scheduler there: dask raises several kinds
            raise StudyError(f"--scheduler {scheduler!r}: cannot reach a Dask scheduler ({type(e).__name__}: "
                             f"{e}); allowed the address of a running dask-scheduler, e.g. tcp://host:8786") from None
    try:
        return _run_into(out, study, cases, remote, workers, progress, plots)
    finally:
        if remote is not None:
            remote.close()


def _run_into(out, study, cases, remote, workers, progress, plots):
    """run_study's part that writes DIR: the plan, the cases (on `remote`, a connected Client, or a
    local cluster of `workers`), the table and the plots."""
    import pandas as pd
    import dask
    from dask.distributed import Client, LocalCluster, as_completed
    from tqdm import tqdm

    made = _make_output_dir(out, "cases")
    try:
        lock = open(os.path.join(out, ".catenary_sim.lock"), "w")
    except OSError as e:
        _unmake(made)
        raise _unwritable(out, e) from None
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        raise StudyError(f"output directory '{out}' is being written by another study run") from None
    plan = {"study": study, "cases": cases}
    plan_path = os.path.join(out, "plan.json")
    if os.path.exists(plan_path):
        try:
            with open(plan_path, encoding="utf-8") as f:
                old = json.load(f)
        except ValueError as e:
            raise StudyError(f"'{plan_path}' is damaged (not the JSON this tool writes: {e}); the cases in "
                             f"'{out}' cannot be matched to a plan: use a new --out, or delete '{out}' to start "
                             "afresh") from None
        if old != json.loads(json.dumps(plan)):
            raise StudyError(f"'{out}' holds the cases of another plan ({_plan_difference(old, plan)}); its cases are "
                             "numbered by that plan and cannot be reused: run the changed study with a new --out "
                             f"(or delete '{out}' to start afresh)")
    else:
        write_atomically(plan_path, json.dumps(plan, indent=1))
    todo = []
    for i in range(len(cases)):
        if _read_case(out, i, len(study["outputs"]), warn=True) is None:
            todo.append(i)

    if todo:
        own = None
        if remote is not None:
            client = remote
        else:
            # Without the workers' statistical profiler: it samples every 10 ms a thread that sits in
            # one C++ call, learns nothing, and takes CPU from the other worker on a 2-core machine
            # (2 workers ran 1.69x one worker with it, 1.8x without; BENCHMARKS.md).
            with dask.config.set({"distributed.worker.profile.enabled": False}):
                own = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(own)
        try:
            futures = {client.submit(run_case, study["scene"], study["overrides"], cases[i], study["outputs"],
                                     _report_dir(out, i) if study["report"] else None,
                                     key=f"case-{study['name']}-{i}", pure=False): i for i in todo}
            bar = tqdm(total=len(cases), initial=len(cases) - len(todo), unit="case", disable=not progress,
                       desc=study["name"])
            for fut in as_completed(futures):
                i = futures[fut]
                record = fut.result()
                record["case"] = i
                # (an output that is not a number, a failed case's, as null: strict JSON)
                record["outputs"] = {k: None if isinstance(v, float) and math.isnan(v) else v
                                     for k, v in record["outputs"].items()}
                write_atomically(_case_path(out, i), json.dumps(record, allow_nan=False))
                bar.update(1)
            bar.close()
        finally:
            if own is not None:
                client.close()
                own.close()

    rows = []
    for i in range(len(cases)):
        r = _read_case(out, i, len(study["outputs"]))
        if r is None:
            raise StudyError(f"case file '{_case_path(out, i)}' is missing or damaged after the run; run the "
                             "study again on the same --out to redo it")
        shown = dict(r["parameters"])
        if study["sampling"] == "grid":  # a list or null value shows as its label
            for p in study["parameters"]:
                shown[p["key"]] = p["labels"][_index_of(p["values"], shown[p["key"]])]
        row = {"case": i, **shown, **r["outputs"], "status": r["status"], "message": r["message"],
               "wall_time_s": r["wall_time_s"]}
        if study["report"]:  # relative to DIR: the table and index.html move with the directory
            row["report"] = os.path.relpath(r["report"], out) if r.get("report") else ""
        rows.append(row)
    table = pd.DataFrame(rows)
    write_atomically(os.path.join(out, "results.csv"), table.to_csv(index=False))
    if study["report"]:
        write_atomically(os.path.join(out, "index.html"), _index_page(study, table))
    if study["sampling"] == "saltelli":
        sens = sobol_indices_from_table(table, study)
        write_atomically(os.path.join(out, "sensitivity.json"), json.dumps(sens, indent=1))
    if plots:
        from . import study_plots
        study_plots.plot_study(study, table, out)
    lock.close()
    return table


def _index_page(study, table):
    """DIR/index.html: the results table with each case's report linked (pandas' to_html)."""
    import html
    shown = table.copy()
    shown["report"] = [f"<a href='{html.escape(p, quote=True)}'>report</a>" if p else "" for p in table["report"]]
    shown["message"] = [html.escape(str(m)) for m in table["message"]]
    body = shown.to_html(index=False, escape=False, na_rep="-", float_format=lambda v: f"{v:.4g}")
    return ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>" + html.escape(study["name"]) + "</title>"
            "<style>body{font-family:sans-serif;margin:1.5em} table{border-collapse:collapse;font-size:0.9em}"
            "td,th{border:1px solid #ccc;padding:0.2em 0.5em;text-align:right}</style></head><body>"
            f"<h1>{html.escape(study['name'])}</h1><p>{len(table)} cases; scene {html.escape(study['scene'])}; "
            "each case's pass report linked.</p>" + body + "</body></html>")


# --------------------------------------------------------------------------------------------
# Sensitivity: Saltelli's scheme, first-order (Saltelli 2010) and total (Jansen 1999) indices
# --------------------------------------------------------------------------------------------
def sobol_indices(f_a, f_b, f_ab, bootstrap=200, seed=0, confidence=0.95):
    """First-order and total Sobol indices from f(A), f(B) (N,) and f(AB_i) (k, N).

    S_i = mean(f_B (f_ABi - f_A)) / V, ST_i = mean((f_A - f_ABi)^2) / (2 V), V the variance of
    f(A) and f(B) together, f centred on their mean (Saltelli et al. 2010, "Variance based sensitivity analysis of model
    output", Comput. Phys. Commun. 181). Confidence intervals by bootstrap over the N rows."""
    f_a, f_b, f_ab = np.asarray(f_a, float), np.asarray(f_b, float), np.asarray(f_ab, float)

    def estimate(idx):
        a, b, ab = f_a[idx], f_b[idx], f_ab[:, idx]
        # Centred first: the S_i estimator's terms are products with f_B, whose mean adds variance
        # (not bias) to it; an output with a large mean and a small spread (a force std of 40 N
        # varying by 1 N between lines) would drown in it. S_T is shift-invariant.
        mu = np.mean(np.concatenate([a, b]))
        a, b, ab = a - mu, b - mu, ab - mu
        var = np.var(np.concatenate([a, b]))
        if not var > 0:
            nan = np.full(ab.shape[0], np.nan)
            return nan, nan
        s1 = np.mean(b * (ab - a), axis=1) / var
        st = 0.5 * np.mean((a - ab) ** 2, axis=1) / var
        return s1, st

    n = f_a.shape[0]
    s1, st = estimate(np.arange(n))
    out = {"S1": s1.tolist(), "ST": st.tolist()}
    if bootstrap > 0:
        rng = np.random.default_rng(seed)
        draws = [estimate(rng.integers(0, n, n)) for _ in range(bootstrap)]
        lo, hi = (1 - confidence) / 2 * 100, (1 + confidence) / 2 * 100
        for name, j in (("S1", 0), ("ST", 1)):
            vals = np.array([d[j] for d in draws])
            out[name + "_conf"] = [np.nanpercentile(vals, lo, axis=0).tolist(), np.nanpercentile(vals, hi, axis=0).tolist()]
    return out


def sobol_indices_from_table(table, study):
    k = len(study["parameters"])
    n = study["samples"]
    result = {"parameters": [p["key"] for p in study["parameters"]], "samples": n, "outputs": {}}
    for o in study["outputs"]:
        y = table[o].to_numpy(dtype=float)
        blocks = y.reshape(k + 2, n)
        if not np.all(np.isfinite(blocks)):
            result["outputs"][o] = {"error": "failed cases: the estimator needs every case"}
            continue
        result["outputs"][o] = sobol_indices(blocks[0], blocks[1], blocks[2:], study["bootstrap"], study["seed"])
    return result


def main(argv=None):
    import argparse
    import sys
    ap = argparse.ArgumentParser(prog="catenary_sim_study", description="Run (or resume) a study of many passes on Dask.")
    ap.add_argument("study", help="study YAML (see catenary_sim.study)")
    ap.add_argument("--out", required=True, help="output directory (cases/, results.csv, plots)")
    ap.add_argument("--workers", type=int, default=2, help="local Dask workers (default 2; ignored with --scheduler)")
    ap.add_argument("--scheduler", help="address of a running dask-scheduler, e.g. tcp://host:8786")
    ap.add_argument("--no-progress", action="store_true", help="no progress bar")
    ap.add_argument("--no-plots", action="store_true", help="no PNG plots")
    a = ap.parse_args(argv)
    try:
        table = run_study(a.study, a.out, a.scheduler, a.workers, not a.no_progress, not a.no_plots)
    except (StudyError, SceneError) as e:
        print(f"catenary_sim_study: {e}", file=sys.stderr, flush=True)
        return 2
    except OSError as e:
        where = f" '{e.filename}'" if e.filename else ""
        print(f"catenary_sim_study:{where} {e.strerror or e}", file=sys.stderr, flush=True)
        return 2
    except MemoryError:
        print("catenary_sim_study: out of memory building the plan; allowed fewer cases (a smaller grid or "
              "fewer samples)", file=sys.stderr, flush=True)
        return 2
    failed = int((table["status"] != "ok").sum())
    print(f"catenary_sim_study: {len(table)} cases, {failed} failed; {os.path.join(a.out, 'results.csv')}")
    return 0
