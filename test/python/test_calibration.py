"""Calibration (catenary_sim.calibration, scripts/calibrate): a record synthesised from a scene with
other damping and dropper stiffness, with sensor noise, is calibrated back to them within the
uncertainty the calibration states; a parameter the pass does not depend on is reported as not
identifiable; a calibration killed part-way and started again on its directory replays its
evaluations and still recovers the parameters."""
import json
import os
import signal
import subprocess
import sys
import time

import pytest
import yaml

from catenary_sim import calibration
from catenary_sim import measurement as cm

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
REFERENCE = os.path.join(ROOT, "config", "reference_55m.yaml")
CLI = os.path.join(ROOT, "scripts", "calibrate")
SHORT = {"line.span_count": 6, "numerics.element_length": 0.5}
TRUTH = {"damping.beta": 3.0e-4, "droppers.axial_stiffness": 1.0e5}


def _kept(directory):
    return [n for n in os.listdir(directory) if n.endswith(".json") and not n.startswith(".")]


def test_a_calibration_recovers_the_parameters_of_a_synthesised_record(tmp_path):
    cm.synthesise_record(REFERENCE, str(tmp_path / "rec.csv"), overrides=dict(SHORT, **TRUTH), speed_profile=250.0,
                         noise_std_N=2.0, seed=3)
    spec = {"scene": REFERENCE, "record": "rec.csv", "overrides": SHORT,
            "parameters": [{"key": "damping.beta", "low": 2e-5, "high": 2e-3, "scale": "log", "initial": 1e-4},
                           {"key": "droppers.axial_stiffness", "low": 2e4, "high": 1e6, "scale": "log",
                            "initial": 2e5},
                           # the allowed uplift is a limit the report checks: the pass does not depend on it
                           {"key": "output.allowed_uplift", "low": 0.05, "high": 0.2}],
            "objective": {"time_history": 1.0}, "optimiser": {"method": "least_squares", "max_evaluations": 30}}
    path = tmp_path / "cal.yaml"
    path.write_text(yaml.safe_dump(spec))
    out = tmp_path / "out"
    cmd = [sys.executable, CLI, str(path), "--out", str(out), "--workers", "2", "--no-report"]
    # Killed (the runner and its Dask workers, SIGKILL) once a few evaluations are kept, then
    # started again on the same directory: it replays them and goes on to the optimum.
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    kept = out / "evaluations"
    deadline = time.time() + 600
    while time.time() < deadline and p.poll() is None and not (kept.is_dir() and len(_kept(kept)) >= 3):
        time.sleep(0.02)
    os.killpg(p.pid, signal.SIGKILL)
    p.wait()
    before = len(_kept(kept))
    assert 3 <= before and not (out / "calibration.json").exists(), "the calibration ended before the kill"
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1200)
    assert r.returncode == 0, r.stdout[-3000:]
    result = json.loads((out / "calibration.json").read_text())
    assert result["replayed"] >= before, result
    assert result["evaluations"] >= 20, result  # a study-sized calibration
    got = {p["key"]: p for p in result["parameters"]}
    for key, true in TRUTH.items():
        p = got[key]
        assert p["identifiable"], p
        # Within three of its stated standard uncertainties, and that uncertainty small enough
        # (10 % of the value) for the check to mean something.
        assert abs(p["value"] - true) <= 3 * p["std"], (key, p)
        assert p["std"] <= 0.1 * p["value"], (key, p)
    assert not got["output.allowed_uplift"]["identifiable"]
    assert "hardly change" in got["output.allowed_uplift"]["why_not"]
    assert result["cost_after"] < result["cost_before"]
    snippet = yaml.safe_load((out / "calibrated.yaml").read_text())
    assert snippet["damping"]["beta"] == pytest.approx(got["damping.beta"]["value"], rel=1e-5)
    # Started again on the same directory: every evaluation is read back, none run.
    again = calibration.calibrate(str(path), str(out), workers=1, report=False)
    assert again["replayed"] == again["evaluations"]
    assert [p["value"] for p in again["parameters"]] == [p["value"] for p in result["parameters"]]


@pytest.mark.parametrize("edit,words", [
    (lambda d: d.update(parameters=[]), "parameters"),
    (lambda d: d["parameters"][0].update(low=5.0, high=1.0), "parameters[0]"),
    (lambda d: d["parameters"][0].update(scale="cubic"), "parameters[0].scale"),
    (lambda d: d.update(objective={"statistics": {"spread": 1}}), "objective.statistics.spread"),
    (lambda d: d.update(optimiser={"method": "simplex"}), "optimiser.method"),
    (lambda d: d.update(colour="red"), "colour"),
    (lambda d: d.update(objective={"statistics": {"std_force_N": "1e0"}}), "objective.statistics.std_force_N"),
    (lambda d: d.update(objective={"time_history": -1}), "objective.time_history"),
    (lambda d: d.update(objective={"statistics": {"std_force_N": 0}, "time_history": 0}), "objective"),
    # a section of the wrong type is refused, not replaced by its default
    (lambda d: d.update(objective={}), "objective"),
    (lambda d: d.update(objective=[]), "objective"),
    (lambda d: d.update(objective=False), "objective"),
    (lambda d: d.update(objective={"statistics": []}), "objective.statistics"),
    (lambda d: d.update(optimiser=0), "optimiser"),
    (lambda d: d.update(optimiser=[]), "optimiser"),
    (lambda d: d.update(overrides=[]), "overrides"),
    (lambda d: d.update(overrides=False), "overrides"),
    (lambda d: d.update(cutoff="abc"), "cutoff"),
    (lambda d: d.update(cutoff=-5), "cutoff"),
    (lambda d: d.update(cutoff="20"), "cutoff"),
    (lambda d: d.update(speed_profile="300"), "speed_profile"),
    (lambda d: d.update(speed_profile=1000), "speed_profile"),
    (lambda d: d.update(optimiser=[1]), "optimiser"),
    (lambda d: d.update(optimiser={"method": "least_squares", "tol": 1}), "optimiser.tol"),
    (lambda d: d.update(meta=5), "meta"),
    # bounds beyond the scene field's own range (damping.beta: [0, 0.1]), found before any pass
    (lambda d: d["parameters"][0].update(high=0.5), "parameters[0].high"),
    (lambda d: d["parameters"][0].update(low=-1e-3), "parameters[0].low"),
    (lambda d: d["parameters"][0].update(key="damping.gamma"), "parameters[0].key"),
    # a field that takes text (the scene's name) takes the bounds too, as text
    (lambda d: d["parameters"][0].update(key="name", low=1, high=2), "parameters[0].key"),
], ids=["no parameters", "bounds reversed", "unknown scale", "unknown statistic", "unknown method", "unknown field",
        "weight as text", "negative weight", "all weights 0", "objective empty", "objective a list",
        "objective false", "statistics a list", "optimiser 0", "optimiser empty list", "overrides a list",
        "overrides false", "cutoff word", "cutoff negative", "cutoff as text",
        "speed as text", "speed beyond 540 km/h", "optimiser a list", "unknown optimiser key", "meta a number",
        "high beyond the scene's range", "low beyond the scene's range", "key not a scene field",
        "key a text field"])
def test_a_bad_calibration_file_is_refused_by_field(tmp_path, edit, words):
    spec = {"scene": REFERENCE, "record": "rec.csv",
            "parameters": [{"key": "damping.beta", "low": 2e-5, "high": 2e-3}]}
    edit(spec)
    path = tmp_path / "cal.yaml"
    path.write_text(yaml.safe_dump(spec))
    with pytest.raises(calibration.CalibrationError) as e:
        calibration.load_calibration(str(path))
    assert f"'{words}'" in str(e.value)


# A short, fast pass: a calibration of it takes seconds.
FAST = {"numerics.preset": "fast", "line.span_count": 6}


def _fast_calibration(tmp_path, name, beta, **fields):
    """A calibration file of damping.beta against a record synthesised with `beta`."""
    cm.synthesise_record(REFERENCE, str(tmp_path / f"{name}.csv"), overrides=dict(FAST, **{"damping.beta": beta}),
                         speed_profile=270.0, noise_std_N=2.0, seed=1)
    spec = {"scene": REFERENCE, "record": f"{name}.csv", "overrides": FAST,
            "parameters": [{"key": "damping.beta", "low": 2e-5, "high": 2e-3, "scale": "log", "initial": 1e-4}],
            "optimiser": {"method": "least_squares", "max_evaluations": 6}}
    spec.update(fields)
    path = tmp_path / f"cal_{name}.yaml"  # not {name}.yaml: that is the record's metadata
    path.write_text(yaml.safe_dump(spec))
    return str(path)


def _run_cli(path, out):
    """scripts/calibrate on one local worker without the before/after reports (output and errors together)."""
    return subprocess.run([sys.executable, CLI, path, "--out", str(out), "--workers", "1", "--no-report"],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)


def test_a_directory_of_another_calibration_replays_none_of_its_evaluations(tmp_path):
    a = _fast_calibration(tmp_path, "a", 3e-4)
    b = _fast_calibration(tmp_path, "b", 6e-4)
    calibration.calibrate(a, str(tmp_path / "shared"), workers=1, report=False)
    # b run where a kept its evaluations gives exactly what b gives on its own: the passes are
    # deterministic, so any replay of a's residuals would show as a difference.
    shared = calibration.calibrate(b, str(tmp_path / "shared"), workers=1, report=False)
    alone = calibration.calibrate(b, str(tmp_path / "alone"), workers=1, report=False)
    assert [p["value"] for p in shared["parameters"]] == [p["value"] for p in alone["parameters"]]
    assert shared["cost_before"] == alone["cost_before"]


def test_an_objective_the_record_cannot_measure_is_refused_before_anything_runs(tmp_path):
    cm.synthesise_record(REFERENCE, str(tmp_path / "bare.csv"), overrides=FAST, speed_profile=270.0, supports=None)
    spec = {"scene": REFERENCE, "record": "bare.csv", "overrides": FAST,
            "parameters": [{"key": "damping.beta", "low": 2e-5, "high": 2e-3, "scale": "log"}],
            "objective": {"statistics": {"max_uplift_m": 1}, "time_history": 0},
            "optimiser": {"max_evaluations": 5}}
    path = tmp_path / "cal.yaml"
    path.write_text(yaml.safe_dump(spec))
    with pytest.raises(calibration.CalibrationError) as e:
        calibration.calibrate(str(path), str(tmp_path / "out"), workers=1, report=False)
    assert "'objective.statistics.max_uplift_m'" in str(e.value) and "uplift_SUPPORT" in str(e.value)
    assert not (tmp_path / "out").exists()


def test_non_convergence_and_a_rough_objective_are_said_plainly(tmp_path):
    # Five passes (the least for one parameter: two for the optimiser, three for the uncertainty)
    # cannot converge; the fast preset's objective is rough at the difference step (the last bit
    # of a parameter moves it by tens of per cent), so no uncertainty can be given.
    path = _fast_calibration(tmp_path, "a", 3e-4, optimiser={"method": "least_squares", "max_evaluations": 5})
    r = _run_cli(path, tmp_path / "out")
    assert r.returncode == 0, r.stdout[-3000:]
    result = json.loads((tmp_path / "out" / "calibration.json").read_text())
    assert not result["converged"] and "NOT CONVERGED" in r.stdout
    assert not result["uncertainty_available"] and "UNCERTAINTY NOT AVAILABLE" in r.stdout
    assert all(p["std"] is None for p in result["parameters"]) and "+-" not in r.stdout
    assert "NOT CONVERGED" in (tmp_path / "out" / "calibrated.yaml").read_text()


def test_max_evaluations_bounds_every_pass_the_calibration_runs(tmp_path):
    # Each distinct parameter point is one pass and one file in evaluations/: the optimiser's
    # function and Jacobian passes and the uncertainty's at the end together stay within the
    # bound, and a calibration stopped by it says so.
    path = _fast_calibration(tmp_path, "a", 3e-4, optimiser={"method": "least_squares", "max_evaluations": 7})
    r = _run_cli(path, tmp_path / "out")
    assert r.returncode == 0, r.stdout[-3000:]
    result = json.loads((tmp_path / "out" / "calibration.json").read_text())
    kept = _kept(tmp_path / "out" / "evaluations")
    assert len(kept) <= 7, (len(kept), result)
    assert result["passes"] == len(kept)
    assert not result["converged"] and "max_evaluations = 7" in result["message"]
    assert "NOT CONVERGED" in r.stdout and "max_evaluations" in r.stdout


def test_what_only_the_comparison_refuses_leaves_no_directory(tmp_path):
    # A record bandwidth beyond the measuring pantograph's range is found by the first pass: it is
    # run before the cluster starts and the output directory is made, and named as the record's.
    path = _fast_calibration(tmp_path, "a", 3e-4)
    meta = yaml.safe_load((tmp_path / "a.yaml").read_text())
    meta["bandwidth_hz"] = 1e6
    (tmp_path / "a.yaml").write_text(yaml.safe_dump(meta))
    with pytest.raises(calibration.CalibrationError) as e:
        calibration.calibrate(path, str(tmp_path / "out"), workers=1, report=False)
    assert "'bandwidth_hz'" in str(e.value) and "output.sensor_bandwidth" in str(e.value)
    assert not (tmp_path / "out").exists()


def test_a_cutoff_longer_than_the_record_is_refused_before_anything_runs(tmp_path):
    # The fast pass's record lasts a few seconds: 0.01 Hz has a period of 100 s.
    path = _fast_calibration(tmp_path, "a", 3e-4, cutoff=0.01)
    with pytest.raises(calibration.CalibrationError) as e:
        calibration.calibrate(path, str(tmp_path / "out"), workers=1, report=False)
    assert "'cutoff'" in str(e.value) and "at least" in str(e.value)
    assert not (tmp_path / "out").exists()


def test_a_diverging_pass_is_said_with_its_parameter_values(tmp_path):
    # A divergence limit of 2 cm lies within the pass's own uplift (several centimetres at
    # 270 km/h), so the watchdog stops the first pass: the command names the parameter values it
    # ran at and exits 3 (as compare_measurement does for a diverging pass), no traceback.
    overrides = dict(FAST, **{"numerics.divergence_limit": 0.02})
    path = _fast_calibration(tmp_path, "a", 3e-4, overrides=overrides)
    r = _run_cli(path, tmp_path / "out")
    assert r.returncode == 3, r.stdout[-3000:]
    assert "the pass at damping.beta = 0.0001: diverged" in r.stdout and "Traceback" not in r.stdout
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("kw,words", [
    ({"workers": 0}, "workers = 0"), ({"workers": -1}, "workers = -1"), ({"workers": "two"}, "workers = 'two'"),
    ({"workers": 2.5}, "workers = 2.5"), ({"path": None}, "path = None"), ({"path": 5}, "path = 5"),
    ({"out": None}, "out = None"), ({"scheduler": 5}, "scheduler = 5"),
    # port 1 is reserved (tcpmux) and not served here: nothing answers
    ({"scheduler": "tcp://127.0.0.1:1"}, "scheduler = 'tcp://127.0.0.1:1'"),
    # a directory that cannot be made (/proc takes no new entries)
    ({"out": "/proc/catenary_sim_out"}, "--out /proc/catenary_sim_out: cannot be written"),
], ids=["workers 0", "workers -1", "workers text", "workers fraction", "path None", "path a number", "out None",
        "scheduler a number", "scheduler unreachable", "out not writable"])
def test_bad_arguments_of_calibrate_are_refused_by_name(tmp_path, kw, words):
    args = {"path": _fast_calibration(tmp_path, "a", 3e-4), "out": str(tmp_path / "out"), "workers": 1,
            "report": False}
    args.update(kw)
    with pytest.raises(calibration.CalibrationError) as e:
        calibration.calibrate(**args)
    assert words in str(e.value)
    assert not (tmp_path / "out").exists()


def test_a_number_yaml_reads_as_text_is_refused_with_how_to_write_it(tmp_path):
    # As in a study file: 2.0e4 (no sign in the exponent) is text to YAML 1.1.
    path = tmp_path / "cal.yaml"
    path.write_text(f"scene: {REFERENCE}\nrecord: rec.csv\n"
                    "parameters: [{key: droppers.axial_stiffness, low: 2.0e4, high: 4.0e+5}]\n")
    with pytest.raises(calibration.CalibrationError,
                       match=r"'parameters\[0\]\.low' = '2\.0e4': a finite number, not text .*write 1\.0e\+308"):
        calibration.load_calibration(str(path))


def test_a_key_given_twice_is_refused_by_name(tmp_path):
    # As in a study file: not the last one silently winning.
    path = tmp_path / "cal.yaml"
    path.write_text(f"scene: {REFERENCE}\nrecord: rec.csv\nparameters: [{{key: damping.beta, low: 2.0e-5, "
                    "high: 2.0e-3}]\noptimiser: {max_evaluations: 10}\noptimiser: {method: least_squares}\n")
    with pytest.raises(calibration.CalibrationError, match=r"line 5: key 'optimiser' is given twice.*first on line 4"):
        calibration.load_calibration(str(path))
    path.write_text(f"scene: {REFERENCE}\nrecord: rec.csv\nparameters: [{{key: damping.beta, low: 2.0e-5, "
                    "high: 2.0e-3}]\nobjective: &o {time_history: 1.0}\nspectrum: *o\n")
    with pytest.raises(calibration.CalibrationError, match="alias"):
        calibration.load_calibration(str(path))
