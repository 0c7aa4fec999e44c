"""`import catenary_sim` under bad and unusual arguments: threads, self-containing and deep
scenes, numpy numbers, paths, indexes, the docs' example, and a fuzz of every argument.

The promise (docs/python.md): every bad scene, override or argument raises catenary_sim.SceneError
(a ValueError) naming the field or argument, the value and what is allowed; nothing crashes or
hangs; a refused command leaves the state as it was. Whatever could crash the interpreter runs in a
child process, so that a crash is a failed test and not a dead pytest."""
import json
import math
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import textwrap

import numpy as np
import pytest
import yaml

import catenary_sim as cs

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
REFERENCE = os.path.join(ROOT, "config", "reference_55m.yaml")
TWO = os.path.join(ROOT, "config", "reference_55m_two_pantographs.yaml")
HIL = os.path.join(ROOT, "config", "reference_55m_hil.yaml")
SHORT = ["line.span_count=4", "output.analysis_spans=[1,3]"]  # a pass of about 3,300 steps


def run_child(code, timeout=180, cwd=ROOT):
    """Runs `code` in a fresh interpreter with this one's sys.path; returns the CompletedProcess.
    A crash (a signal) shows as a negative return code, a hang as TimeoutExpired."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd, env=env, timeout=timeout,
                          capture_output=True, text=True)


def reference():
    with open(REFERENCE) as f:
        return yaml.safe_load(f)


# Threads -------------------------------------------------------------------------------------------

def test_one_simulation_from_several_threads_neither_crashes_nor_mixes_its_calls():
    # step() runs without the GIL, so other threads' calls on the same object run meanwhile. Each
    # call must act on the pass as a whole: steps taken by four threads at once add up to the steps
    # of one thread alone, to the bit (the same deterministic steps in some order of whole calls);
    # while threads step, reset and read for a bounded time, every series read is one pass's (equal
    # column lengths, time strictly increasing) and the process survives.
    r = run_child(f"""
        import sys, threading, time
        import numpy as np
        import catenary_sim as cs
        ref, short = {REFERENCE!r}, {SHORT!r}

        sim = cs.Simulation(ref, overrides=short, sample_rate=0)
        taken = []
        def stepper():
            for _ in range(20):
                taken.append(sim.step(25))
        threads = [threading.Thread(target=stepper) for _ in range(4)]
        for t in threads: t.start()
        for t in threads: t.join()
        alone = cs.Simulation(ref, overrides=short, sample_rate=0)
        alone.step(2000)
        assert sum(taken) == 2000 and sim.steps == 2000, (sum(taken), sim.steps)
        assert np.array_equal(sim.displacements, alone.displacements)
        assert sim.series()["time_s"].shape == alone.series()["time_s"].shape

        stop = time.monotonic() + 3.0
        errors = []
        def guarded(f):
            def loop():
                try:
                    while time.monotonic() < stop:
                        f()
                except BaseException as e:
                    errors.append(repr(e))
            return loop
        def read_series():
            s = sim.series()
            n = s["time_s"].shape[0]
            assert n >= 1 and all(a.shape == (n,) for a in s.values())
            assert np.all(np.diff(s["time_s"]) > 0.0)
        def read_statistics():
            st = sim.statistics()
            assert st["steps"] >= 0
        def read_state():
            u = np.array(sim.displacements)
            assert u.shape == (sim.dofs,) and np.all(np.isfinite(u))
            sim.pantograph_state(0)
        work = [lambda: sim.step(40), lambda: sim.step(7), lambda: (time.sleep(0.01), sim.reset()),
                read_series, read_statistics, read_state]
        threads = [threading.Thread(target=guarded(f)) for f in work]
        for t in threads: t.start()
        for t in threads: t.join()
        assert not errors, errors
        sim.reset()
        sim.step(100)
        assert sim.series()["time_s"].shape == (101,)  # the reset pass's initial row and its 100 steps
        print("ok")
    """)
    assert r.returncode == 0 and r.stdout.strip().endswith("ok"), (r.returncode, r.stderr[-3000:])


# Scenes and overrides as Python objects ------------------------------------------------------------

def test_a_scene_that_contains_itself_or_nests_too_deep_is_refused():
    r = run_child(f"""
        import json, yaml
        import catenary_sim as cs
        ref = {REFERENCE!r}
        scene = yaml.safe_load(open(ref))
        out = {{}}

        def refusal(f):
            try:
                f()
            except cs.SceneError as e:
                return [e.field, str(e)]
            except BaseException as e:
                return ["not a SceneError", repr(e)[:300]]
            return ["accepted", ""]

        looped = dict(scene); looped["line"] = dict(scene["line"]); looped["line"]["again"] = looped
        out["scene"] = refusal(lambda: cs.Simulation(looped))
        out["check"] = refusal(lambda: cs.check_scene(looped))
        loop_list = [1.0]; loop_list.append(loop_list)
        out["override"] = refusal(lambda: cs.Simulation(ref, overrides={{"droppers.positions": loop_list}}))
        deep = 0.0
        for _ in range(100000):
            deep = [deep]
        out["deep"] = refusal(lambda: cs.Simulation(ref, overrides={{"droppers.positions": deep}}))
        deep_scene = dict(scene); d = deep_scene
        for _ in range(100000):
            d["x"] = {{}}; d = d["x"]
        out["deep_scene"] = refusal(lambda: cs.check_scene(deep_scene))
        bomb = [0.0]
        for _ in range(9):
            bomb = [bomb] * 9          # 9 levels of 9 references: 387 million values written out
        out["bomb"] = refusal(lambda: cs.check_scene(dict(scene, extra=bomb)))
        print(json.dumps(out))
    """, timeout=120)
    assert r.returncode == 0, (r.returncode, r.stderr[-3000:])
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert out["scene"][0] == "line.again" and "contains itself" in out["scene"][1], out
    assert out["check"][0] == "line.again", out
    assert out["override"][0] == "droppers.positions[1]" and "contains itself" in out["override"][1], out
    for k in ("deep", "deep_scene"):
        assert out[k][0] not in ("accepted", "not a SceneError") and "deeper than" in out[k][1], out
    assert out["bomb"][0] == "extra" and "values" in out["bomb"][1], out


def test_an_object_used_twice_in_a_scene_is_written_out_in_full():
    # YAML would write a shared object once and alias it; the scene readers need no aliases.
    scene = reference()
    shared = [0.3, -0.3]
    scene["stagger"] = {"contact_wire": shared, "messenger": list(shared)}
    alone = cs.Simulation(scene, overrides=SHORT).pantograph_state(0)
    scene["stagger"]["messenger"] = shared
    assert cs.Simulation(scene, overrides=SHORT).pantograph_state(0) == alone


def test_numpy_numbers_are_numbers():
    plain = {"train.speed_kmh": 250.0, "line.span_count": 4, "output.analysis_spans": [1, 3],
             "contact.stiffness": 50000.0, "pantographs.0.static_uplift": 120.0}
    numpy = {"train.speed_kmh": np.float64(250.0), "line.span_count": np.int64(4),
             "output.analysis_spans": np.array([1, 3]), "contact.stiffness": np.float32(50000.0),
             "pantographs.0.static_uplift": np.array(120.0)}
    a = cs.Simulation(REFERENCE, overrides=plain)
    b = cs.Simulation(REFERENCE, overrides=numpy, speed_kmh=np.float32(250.0), sample_rate=np.int32(100))
    a.step(200)
    b.step(np.int64(200))
    assert np.array_equal(a.displacements, b.displacements)
    scene = reference()
    scene["line"]["span_count"] = np.int64(4)
    scene["output"] = {"analysis_spans": np.array([1, 3])}
    scene["contact"]["stiffness"] = np.float64(50000.0)
    scene["train"] = {"speed_kmh": np.float64(250.0)}
    c = cs.Simulation(scene, overrides={"pantographs.0.static_uplift": 120.0})
    c.step(200)
    assert np.array_equal(a.displacements, c.displacements)
    b.set_speed(np.float64(80.0))
    b.set_uplift(np.float32(110.0), pantograph=np.int64(0))
    assert b.pantograph_state(np.int16(0))["uplift_N"] == 110.0


def test_paths_are_accepted_wherever_a_path_is():
    path = pathlib.Path(REFERENCE)
    cs.check_scene(path, overrides=SHORT)
    sim = cs.Simulation(path, overrides=SHORT)
    stats, _ = cs.run_pass(path, overrides=SHORT)
    assert stats["steps"] > 0
    sim.step(10)
    with tempfile.TemporaryDirectory() as d:
        sim.write_files(pathlib.Path(d) / "out")
        assert (pathlib.Path(d) / "out" / "stats.json").exists()


@pytest.mark.parametrize("call, argument", [
    (lambda: cs.Simulation(REFERENCE, speed_kmh="fast"), "speed_kmh"),
    (lambda: cs.Simulation(REFERENCE, speed_kmh=[250]), "speed_kmh"),
    (lambda: cs.Simulation(REFERENCE, sample_rate="100"), "sample_rate"),
    (lambda: cs.Simulation(REFERENCE, sample_rate=[100]), "sample_rate"),
    (lambda: cs.Simulation(REFERENCE, overrides={"train.speed_kmh": {1, 2}}), "train.speed_kmh"),
    (lambda: cs.Simulation(dict(reference(), line={"span_length": 1j})), "line.span_length"),
    (lambda: cs.Simulation(REFERENCE, overrides={1: 2}), "overrides"),
    (lambda: cs.Simulation(REFERENCE, overrides=["train.speed_kmh=250", 3]), "overrides[1]"),
    (lambda: cs.Simulation(REFERENCE, overrides=42), "overrides"),
    (lambda: cs.Simulation(42), "scene"),
    (lambda: cs.check_scene(b"config/reference_55m.yaml"), "scene"),
])
def test_arguments_of_the_wrong_type_raise_scene_error_naming_them(call, argument):
    with pytest.raises(cs.SceneError) as e:
        call()
    assert e.value.field == argument, str(e.value)
    assert e.value.value is not None and e.value.allowed, str(e.value)


def test_commands_with_arguments_of_the_wrong_type_raise_scene_error_naming_them():
    sim = cs.Simulation(REFERENCE, overrides=SHORT)
    for call, argument in ((lambda: sim.step("10"), "n"), (lambda: sim.step([1]), "n"), (lambda: sim.step(0.5), "n"),
                           (lambda: sim.run(max_steps="all"), "max_steps"),
                           (lambda: sim.set_speed("80"), "speed_mps"), (lambda: sim.set_speed(None), "speed_mps"),
                           (lambda: sim.set_max_acceleration([1.0]), "accel_mps2"),
                           (lambda: sim.set_uplift("120"), "force_n"),
                           (lambda: sim.set_external_force({}), "force_n"),
                           (lambda: sim.statistics("now"), "wall_time_s"),
                           (lambda: sim.pantograph_state("0"), "index")):
        with pytest.raises(cs.SceneError) as e:
            call()
        assert e.value.field == argument, str(e.value)
        assert e.value.allowed, str(e.value)
    assert sim.steps == 0


# Reset and indexes ----------------------------------------------------------------------------------

def test_reset_keeps_the_sample_rate():
    # 100 Hz over 2,000 steps of dt: 2000 dt * 100 rows plus the initial one, the same before and
    # after a reset (time keeps running across a reset, so the sampling phase may move one row).
    sim = cs.Simulation(REFERENCE, overrides=SHORT, sample_rate=100)
    sim.step(2000)
    before = sim.series()["time_s"].shape[0]
    expected = 2000 * sim.dt * 100 + 1
    assert abs(before - expected) <= 1
    sim.reset()
    sim.step(2000)
    after = sim.series()["time_s"].shape[0]
    assert abs(after - expected) <= 1, (before, after)


def test_pantograph_indexes_out_of_range_or_not_integers_are_refused_and_change_nothing():
    sim = cs.Simulation(TWO)
    sim.step(5)
    names = sim.pantograph_names
    assert len(names) == 2

    def uplifts():
        return [sim.pantograph_state(i)["uplift_N"] for i in range(2)]

    before = uplifts()
    for bad in (-2, 2, 100, 0.5, 1.0000001, True, "0", None if False else [0], float("nan")):
        with pytest.raises(cs.SceneError) as e:
            sim.set_uplift(150.0, pantograph=bad)
        assert e.value.field == "pantograph", str(e.value)
        assert "0 to 1" in e.value.allowed and "-1" in e.value.allowed, str(e.value)
        assert uplifts() == before
        with pytest.raises(cs.SceneError) as e:
            sim.pantograph_state(bad)
        assert e.value.field == "index" and "0 to 1" in e.value.allowed, str(e.value)
    sim.set_uplift(150.0, pantograph=1)
    assert uplifts() == [before[0], 150.0]
    sim.set_uplift(140.0, pantograph=-1)  # -1: every pantograph
    assert uplifts() == [140.0, 140.0]


def test_external_force_indexes_are_checked_and_a_refusal_changes_nothing():
    sim = cs.Simulation(HIL, overrides=SHORT)
    sim.set_external_force(90.0)
    sim.step(5)
    u = sim.displacements.copy()
    for bad in (-1, 1, 0.5, "0"):
        with pytest.raises(cs.SceneError) as e:
            sim.set_external_force(95.0, pantograph=bad)
        assert e.value.field == "pantograph" and "0" in e.value.allowed, str(e.value)
    for bad in (float("nan"), 1e9, -51.0):
        with pytest.raises(cs.SceneError) as e:
            sim.set_external_force(bad)
        assert e.value.field == "force_n" and "-50 to 2000 N" in e.value.allowed, str(e.value)
    sim.step(5)
    ref = cs.Simulation(HIL, overrides=SHORT)
    ref.set_external_force(90.0)
    ref.step(10)
    assert np.array_equal(sim.displacements, ref.displacements)
    assert not np.array_equal(u, sim.displacements)
    # A pantograph that is not external: the message says which are.
    with pytest.raises(cs.SceneError) as e:
        cs.Simulation(REFERENCE, overrides=SHORT).set_external_force(90.0)
    assert e.value.field == "pantograph" and "external" in str(e.value)


def test_numbers_in_messages_are_written_as_numbers():
    sim = cs.Simulation(REFERENCE, overrides=SHORT)
    # A given value whole (its shortest round trip: one just past a limit must not read as the
    # limit), without trailing zeros.
    for call, shown in ((lambda: sim.set_speed(300.0), "300 m/s"), (lambda: sim.set_speed(1000 / 3), "333.3333333333333 m/s"),
                        (lambda: sim.set_uplift(1500.0), "1500 N"), (lambda: sim.set_max_acceleration(25.0), "25 m/s^2")):
        with pytest.raises(cs.SceneError) as e:
            call()
        assert shown in str(e.value), str(e.value)
        assert not re.search(r"\d\.\d*0000\b", str(e.value)), str(e.value)
        assert e.value.value is not None and e.value.allowed and not re.search(r"\.0000", e.value.allowed)
    with pytest.raises(cs.SceneError) as e:
        cs.Simulation(single_wire_at_rest()).run(max_steps=10)
    assert "inf steps" in str(e.value) and "0 m/s" in str(e.value) and "max_steps = 10" in str(e.value), str(e.value)


def single_wire_at_rest():
    return {"name": "single_wire", "line": {"span_length": 50.0, "span_count": 1},
            "contact_wire": {"linear_mass": 1.35, "bending_stiffness": 0.0, "tension": 20000.0},
            "pantographs": [{"name": "force", "type": "moving_force", "static_uplift": 100.0}],
            "train": {"speed": 0.0, "start": 25.0}, "numerics": {"element_length": 0.5},
            "output": {"analysis_spans": [0, 1]}}


# The docs ----------------------------------------------------------------------------------------

def python_md_blocks():
    """The indented code blocks of docs/python.md (four spaces after a blank line, as Markdown)."""
    with open(os.path.join(ROOT, "docs", "python.md")) as f:
        lines = f.read().splitlines()
    blocks, current, previous_blank = [], None, True
    for line in lines:
        if current is not None:
            if line.startswith("    ") or not line.strip():
                current.append(line[4:])
                continue
            blocks.append("\n".join(current).rstrip() + "\n")
            current = None
        if line.startswith("    ") and previous_blank:
            current = [line[4:]]
        previous_blank = not line.strip()
    if current is not None:
        blocks.append("\n".join(current).rstrip() + "\n")
    return blocks


def test_the_examples_of_docs_python_md_run_as_written():
    # Run from the repository root, as the page's relative paths are.
    blocks = python_md_blocks()
    assert blocks and any("cs.Simulation(" in b for b in blocks)
    for block in blocks:
        r = run_child(block, timeout=600)
        assert r.returncode == 0, (block, r.stderr[-3000:])


# Fuzz -------------------------------------------------------------------------------------------

def test_fuzz_of_every_argument_raises_scene_error_naming_it():
    # Every number argument with values of the wrong type, non-finite, huge or negative, on one
    # object (and the constructor's, overrides and a scene's value): each must raise SceneError
    # naming the argument or field, no crash (a child process), no hang (its timeout), and the
    # object must be as it was afterwards. (run(max_steps=inf) on a pass at speed 0 never ended.)
    r = run_child(f"""
        import json
        import numpy as np
        import yaml
        import catenary_sim as cs
        ref, hil, short = {REFERENCE!r}, {HIL!r}, {SHORT!r}
        bad_numbers = ["x", "", b"1", [1.0], (1.0,), {{}}, None, object(), 1j, np.array([1.0, 2.0]),
                       float("nan"), float("inf"), -float("inf"), np.float32("inf"), 1e308, -1e308,
                       10 ** 30, -10 ** 30, 2 ** 63, -1, -1e-300, True]
        sim = cs.Simulation(ref, overrides=short)
        sim.step(3)
        hsim = cs.Simulation(hil, overrides=short)
        at_rest = cs.Simulation(ref, overrides=short + ["train.speed_kmh=0"])  # a run() that never ends
        scene = yaml.safe_load(open(ref))

        def with_span(v):
            s = dict(scene, line=dict(scene["line"], span_length=v))
            return cs.check_scene(s)

        def state():
            return (sim.displacements.tolist(), sim.speed, sim.pantograph_state(0), sim.steps,
                    hsim.displacements.tolist(), at_rest.steps)

        calls = {{  # what is called: (the field the error must name, call)
            "speed_kmh": ("speed_kmh", lambda v: cs.Simulation(ref, overrides=short, speed_kmh=v)),
            "sample_rate": ("sample_rate", lambda v: cs.Simulation(ref, overrides=short, sample_rate=v)),
            "step": ("n", lambda v: sim.step(v)),
            "run": ("max_steps", lambda v: at_rest.run(max_steps=v)),
            "set_speed": ("speed_mps", lambda v: sim.set_speed(v)),
            "set_max_acceleration": ("accel_mps2", lambda v: sim.set_max_acceleration(v)),
            "set_uplift": ("force_n", lambda v: sim.set_uplift(v)),
            "set_uplift pantograph": ("pantograph", lambda v: sim.set_uplift(100.0, pantograph=v)),
            "pantograph_state": ("index", lambda v: sim.pantograph_state(v)),
            "statistics": ("wall_time_s", lambda v: sim.statistics(v)),
            "set_external_force": ("force_n", lambda v: hsim.set_external_force(v)),
            "set_external_force pantograph": ("pantograph", lambda v: hsim.set_external_force(90.0, pantograph=v)),
            "override": ("train.speed_kmh", lambda v: cs.Simulation(ref, overrides={{"train.speed_kmh": v}})),
            "scene": ("line.span_length", with_span),
        }}
        # What some of them take: a sample rate or a wall time of any size (as long as finite), -1
        # for every pantograph, None for the default (an override's None removes the field: the
        # scene's value stays), a measured force down to -50 N (load-cell noise, taken as 0).
        huge = ("1e+308", "1000000000000000000000000000000", "9223372036854775808")
        valid = {{("sample_rate", h) for h in huge}} | {{("statistics", h) for h in huge}}
        valid |= {{("set_uplift pantograph", "-1"), ("override", "None"), ("speed_kmh", "None"),
                   ("sample_rate", "None"), ("set_external_force", "-1"), ("set_external_force", "-1e-300")}}
        before = state()
        wrong = []
        for name, (field, call) in calls.items():
            for v in bad_numbers:
                try:
                    call(v)
                except cs.SceneError as e:
                    if e.field != field or not e.allowed or e.value is None:
                        wrong.append([name, repr(v), "field", e.field, str(e)[:300]])
                except BaseException as e:
                    wrong.append([name, repr(v), type(e).__name__, str(e)[:300]])
                else:
                    if (name, repr(v)) not in valid:
                        wrong.append([name, repr(v), "accepted"])
        # Overrides as simulate_pass --set takes them: non-finite, huge, negative, of another type.
        for text in (".nan", "nan", ".inf", "-.inf", "1e999", "-1e999", "1e300", "-3", "[1]", "{{a: 1}}", "true", "'x'"):
            for key, field in (("train.speed_kmh", "train.speed_kmh"), ("pantographs.0.static_uplift",
                               "pantographs[0].static_uplift"), ("line.span_count", "line.span_count")):
                try:
                    cs.Simulation(ref, overrides=short + [f"{{key}}={{text}}"])
                except cs.SceneError as e:
                    if e.field != field or not e.allowed:
                        wrong.append([key, text, "field", e.field, str(e)[:300]])
                except BaseException as e:
                    wrong.append([key, text, type(e).__name__, str(e)[:300]])
                else:
                    wrong.append([key, text, "accepted"])
        for i, o in enumerate((["train.speed_kmh"], [3], ["=3"])):
            try:
                cs.Simulation(ref, overrides=o)
            except cs.SceneError as e:
                if not e.field or not e.allowed:
                    wrong.append([repr(o), "field", e.field, str(e)[:300]])
            except BaseException as e:
                wrong.append([repr(o), type(e).__name__, str(e)[:300]])
            else:
                wrong.append([repr(o), "accepted"])
        assert state() == before, "a refused call changed the state"
        print(json.dumps(wrong))
    """, timeout=300)
    assert r.returncode == 0, (r.returncode, r.stderr[-3000:])
    wrong = json.loads(r.stdout.strip().splitlines()[-1])
    assert not wrong, "\n".join(map(str, wrong))
