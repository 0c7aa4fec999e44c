"""Studies (catenary_sim.study): the Sobol estimator against the Ishigami function's published
indices, a study on a 2-worker local Dask cluster killed half-way and resumed, failed cases, and
fields the scene lacks refused before any case runs."""
import json
import math
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
import yaml

from catenary_sim import study

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
REFERENCE = os.path.join(ROOT, "config", "reference_55m.yaml")
STUDY_CLI = os.path.join(ROOT, "scripts", "catenary_sim_study")


def test_sobol_indices_of_the_ishigami_function():
    # Ishigami (a = 7, b = 0.1; Ishigami & Homma 1990), X_i uniform on [-pi, pi]: published
    # indices S1 = (0.3139, 0.4424, 0), ST = (0.5576, 0.4424, 0.2437) (Saltelli et al. 2008,
    # "Global Sensitivity Analysis. The Primer", sec. 4.6). With N = 2^14 scrambled Sobol base
    # samples the estimators' error is well under 0.02 (Saltelli et al. 2010, fig. 1-2); 0.03.
    s = {"sampling": "saltelli", "samples": 2 ** 14, "seed": 3,
         "parameters": [{"key": f"x{i}", "distribution": {"type": "uniform", "low": -math.pi, "high": math.pi}}
                        for i in range(3)]}
    cases = study.make_cases(s)
    x = np.array([[c[f"x{i}"] for i in range(3)] for c in cases])
    y = np.sin(x[:, 0]) + 7.0 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])
    n = s["samples"]
    blocks = y.reshape(5, n)
    r = study.sobol_indices(blocks[0], blocks[1], blocks[2:], bootstrap=50, seed=1)
    assert r["S1"] == pytest.approx([0.3139, 0.4424, 0.0], abs=0.03)
    assert r["ST"] == pytest.approx([0.5576, 0.4424, 0.2437], abs=0.03)
    for name in ("S1", "ST"):  # the intervals hold the estimate
        lo, hi = r[name + "_conf"]
        assert all(a <= v <= b for a, v, b in zip(lo, r[name], hi))


def write_study(path, **fields):
    doc = {"name": "t", "scene": REFERENCE, "overrides": {"numerics.preset": "balanced"},
           "outputs": ["pantographs.0.std_force_N", "pantographs.0.mean_force_N"]}
    doc.update(fields)
    with open(path, "w") as f:
        yaml.safe_dump(doc, f)
    return path


def run_cli(study_path, out, **kw):
    env = dict(os.environ)
    return subprocess.Popen([sys.executable, STUDY_CLI, study_path, "--out", out, "--no-progress", "--no-plots"],
                            env=env, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, **kw)


def test_a_study_killed_half_way_resumes_to_the_same_table(tmp_path):
    spec = write_study(str(tmp_path / "s.yaml"), sampling="lhs", samples=16, seed=5,
                       parameters=[{"key": "pantographs.0.static_uplift",
                                    "distribution": {"type": "uniform", "low": 80, "high": 120}},
                                   {"key": "train.speed_kmh",
                                    "distribution": {"type": "truncated_normal", "mean": 280, "std": 20,
                                                     "low": 200, "high": 320}}])
    whole, part = str(tmp_path / "whole"), str(tmp_path / "part")
    p = run_cli(spec, whole)
    assert p.wait(timeout=600) == 0, p.stdout.read().decode()
    # The same study, killed (the runner and its Dask workers, SIGKILL) once a case is written.
    p = run_cli(spec, part)
    cases = os.path.join(part, "cases")
    deadline = time.time() + 300
    while time.time() < deadline and not (os.path.isdir(cases) and any(n.endswith(".json") and not n.startswith(".")
                                                                         for n in os.listdir(cases))):
        time.sleep(0.02)
    os.killpg(p.pid, signal.SIGKILL)
    p.wait()
    done = [n for n in os.listdir(cases) if n.endswith(".json") and not n.startswith(".")]
    assert 1 <= len(done) < 16, f"{len(done)} cases done before the kill: nothing left to resume"
    p = run_cli(spec, part)
    assert p.wait(timeout=600) == 0, p.stdout.read().decode()
    a = pd.read_csv(os.path.join(whole, "results.csv")).drop(columns=["wall_time_s"])
    b = pd.read_csv(os.path.join(part, "results.csv")).drop(columns=["wall_time_s"])
    pd.testing.assert_frame_equal(a, b)  # the passes are deterministic: equal, not close
    assert (a["status"] == "ok").all()


def test_failed_cases_are_recorded_and_the_others_go_on(tmp_path):
    # A dt the scene reads but the model's stability limit refuses: only the build finds it.
    spec = write_study(str(tmp_path / "s.yaml"), sampling="grid",
                       parameters=[{"key": "numerics.dt", "values": [0.0005, 0.01, 0.0006]}])
    table = study.run_study(spec, str(tmp_path / "out"), workers=2, progress=False, plots=True)
    assert list(table["status"]) == ["ok", "failed", "ok"]
    assert "numerics.dt" in table["message"][1] and "stability limit" in table["message"][1]
    assert math.isnan(table["pantographs.0.std_force_N"][1])
    assert os.path.exists(str(tmp_path / "out" / "pantographs_0_std_force_N.png"))
    # The failed case's file is strict JSON: its outputs null, not NaN.
    with open(tmp_path / "out" / "cases" / "000001.json") as f:
        record = json.loads(f.read(), parse_constant=lambda c: pytest.fail(f"{c} in a case file: not JSON"))
    assert record["outputs"]["pantographs.0.std_force_N"] is None


def test_fields_the_scene_lacks_are_refused_before_any_case_runs(tmp_path):
    # A misspelt parameter key or output, or overrides the scene refuses, would fail every case:
    # refused by name before the output directory is made.
    grid = [{"key": "pantographs.0.static_uplift", "values": [100, 120]}]
    bad = {"parameters[0].key": dict(parameters=[{"key": "steady_arms.stifness", "values": [1, 2]}]),
           "outputs[1]": dict(parameters=grid, outputs=["pantographs.0.std_force_N", "pantographs.0.std_forc_N"]),
           "outputs[0]": dict(parameters=grid, outputs=["pantographs.3.std_force_N"]),
           "overrides": dict(parameters=grid, overrides={"numerics.dt": -1})}
    for field, fields in bad.items():
        out = tmp_path / ("out_" + field.replace("[", "_").replace("]", ""))
        with pytest.raises(study.StudyError, match=re.escape(field)):
            study.run_study(write_study(str(tmp_path / "s.yaml"), **fields), str(out), workers=1, progress=False)
        assert not out.exists(), field
    # The command says so with status 2.
    p = run_cli(write_study(str(tmp_path / "s.yaml"), **bad["outputs[1]"]), str(tmp_path / "cli"))
    assert p.wait(timeout=300) == 2
    assert "outputs[1]" in p.stdout.read().decode()
    assert not (tmp_path / "cli").exists()


def test_values_the_scene_refuses_are_refused_before_any_case_runs(tmp_path):
    # A grid value or a sampled value no field allows would fail its case only once the cases
    # before it had run: refused up front, naming the study's field, the case and the scene's words.
    grid = dict(parameters=[{"key": "pantographs.0.static_uplift", "values": [100, -5, 120]}])
    tails = dict(sampling="random", samples=400, seed=1,
                 parameters=[{"key": "pantographs.0.static_uplift",
                              "distribution": {"type": "normal", "mean": 100, "std": 50}}])  # 2 % below 0
    across = dict(parameters=[{"key": "line.span_length", "values": [55.0, 40.0]}])  # the droppers lie beyond 40 m
    for name, fields, field, words in [
            ("grid", grid, "parameters[0].values[1]", "pantographs[0].static_uplift"),
            ("tails", tails, "parameters[0].distribution", "pantographs[0].static_uplift"),
            ("across", across, "parameters", "droppers")]:
        out = tmp_path / ("out_" + name)
        with pytest.raises(study.StudyError) as e:
            study.run_study(write_study(str(tmp_path / "s.yaml"), **fields), str(out), workers=1, progress=False)
        assert f"study field '{field}'" in str(e.value), str(e.value)
        assert words in str(e.value), str(e.value)
        assert not out.exists(), name


def test_bad_study_files_name_the_field(tmp_path):
    with pytest.raises(study.StudyError, match="sampling"):
        study.load_study(write_study(str(tmp_path / "a.yaml"), sampling="quasi", parameters=[{"key": "a", "values": [1]}]))
    with pytest.raises(study.StudyError, match=r"parameters\[0\].distribution.std"):
        study.load_study(write_study(str(tmp_path / "b.yaml"), sampling="random", samples=4,
                                     parameters=[{"key": "a", "distribution": {"type": "normal", "mean": 0, "std": -1}}]))
    with pytest.raises(study.StudyError, match="samples"):
        study.load_study(write_study(str(tmp_path / "c.yaml"), sampling="lhs",
                                     parameters=[{"key": "a", "distribution": {"type": "uniform", "low": 0, "high": 1}}]))
    with pytest.raises(study.StudyError, match="spam"):
        study.load_study(write_study(str(tmp_path / "d.yaml"), spam=1, parameters=[{"key": "a", "values": [1]}]))
    # Fields that could not act under the study's sampling: refused, not ignored.
    with pytest.raises(study.StudyError, match=r"'parameters\[0\]\.distribution' = .*only with sampling"):
        study.load_study(write_study(str(tmp_path / "f.yaml"), parameters=[
            {"key": "a", "values": [1], "distribution": {"type": "uniform", "low": 1, "high": 2}}]))
    with pytest.raises(study.StudyError, match=r"'samples' = -7: only with sampling"):
        study.load_study(write_study(str(tmp_path / "g.yaml"), samples=-7, parameters=[{"key": "a", "values": [1]}]))
    with pytest.raises(study.StudyError, match=r"'seed' = 3: only with sampling"):  # a grid draws nothing
        study.load_study(write_study(str(tmp_path / "s.yaml"), seed=3, parameters=[{"key": "a", "values": [1]}]))
    with pytest.raises(study.StudyError, match=r"'bootstrap' = 50: only with sampling: saltelli"):
        study.load_study(write_study(str(tmp_path / "b.yaml"), sampling="lhs", samples=4, bootstrap=50, parameters=[
            {"key": "a", "distribution": {"type": "uniform", "low": 1, "high": 2}}]))
    with pytest.raises(study.StudyError, match=r"'parameters\[0\]\.values' = \[1\]: only with sampling: grid"):
        study.load_study(write_study(str(tmp_path / "v.yaml"), sampling="random", samples=4, parameters=[
            {"key": "a", "values": [1], "distribution": {"type": "uniform", "low": 1, "high": 2}}]))
    # An integers distribution's bounds are whole numbers (its draws are low, low + 1, ...).
    for bound, low, high in (("low", 0.5, 2), ("high", 0, 1.2)):
        with pytest.raises(study.StudyError, match=rf"'parameters\[0\]\.distribution\.{bound}' = .*a whole number"):
            study.load_study(write_study(str(tmp_path / "i.yaml"), sampling="random", samples=4, parameters=[
                {"key": "a", "distribution": {"type": "integers", "low": low, "high": high}}]))
    # A number YAML 1.1 reads as text: refused with how to write it.
    path = tmp_path / "t.yaml"
    path.write_text(f"scene: {REFERENCE}\noutputs: [a]\nsampling: random\nsamples: 4\nparameters:\n"
                    "  - {key: a, distribution: {type: uniform, low: -1.0e308, high: 1.0e+308}}\n")
    with pytest.raises(study.StudyError, match=r"distribution\.low' = '-1\.0e308': a finite number, not text .*1\.0e\+308"):
        study.load_study(str(path))
    # Bounds each finite but so far apart that high - low overflows: the samples would be inf.
    with pytest.raises(study.StudyError, match=r"parameters\[0\]\.distribution\.high' = 1e\+308.*overflows"):
        study.load_study(write_study(str(tmp_path / "h.yaml"), sampling="random", samples=4,
                                     parameters=[{"key": "a", "distribution": {"type": "uniform", "low": -1.0e308,
                                                                               "high": 1.0e308}}]))
    with pytest.raises(study.StudyError, match=r"parameters\[0\]\.distribution\.std' = 1e\+308"):
        study.load_study(write_study(str(tmp_path / "n.yaml"), sampling="random", samples=4,
                                     parameters=[{"key": "a", "distribution": {"type": "normal", "mean": 0,
                                                                               "std": 1.0e308}}]))
    # Overrides of another type than a map are refused, not taken as none.
    for bad in ([], 0, False, "numerics.preset=fast"):
        with pytest.raises(study.StudyError, match=r"study field 'overrides' = .*a map"):
            study.load_study(write_study(str(tmp_path / "o.yaml"), overrides=bad, parameters=[{"key": "a",
                                                                                               "values": [1]}]))
    assert study.load_study(write_study(str(tmp_path / "o.yaml"), overrides=None,
                                        parameters=[{"key": "a", "values": [1]}]))["overrides"] == {}
    # NaN or infinity in the overrides (plan.json holds neither) is refused by its key and value.
    for bad in (float("nan"), float("inf"), [1.0, float("nan")]):
        with pytest.raises(study.StudyError, match=r"study field 'overrides\.bridle\.length' = .*(nan|inf)"):
            study.load_study(write_study(str(tmp_path / "e.yaml"), overrides={"bridle.length": bad},
                                         parameters=[{"key": "a", "values": [1]}]))


def test_grid_values_may_be_lists_and_null_with_labels(tmp_path):
    # The overlap-design study's kind of grid: null (the scene's rule, eq. 6-8), a fixed rise, and a
    # list-valued field (where the transition droppers hang), on three axes. Each case must be the
    # pass run_pass gives for the same overrides (deterministic: equal), the table must show the
    # labels, and the three-parameter grid must give its maps.
    import catenary_sim as cs
    calpe = os.path.join(ROOT, "config", "calpe_example.yaml")
    spec = write_study(str(tmp_path / "s.yaml"), scene=calpe, overrides={"output.analysis_spans": [2, 3]},
                       sampling="grid", outputs=["pantographs.0.std_force_N", "section_support_rises.0.last_m"],
                       parameters=[{"key": "overlap.support_rise", "values": [None, 0.06], "labels": ["eq. 6-8", "d 0.06"]},
                                   {"key": "droppers.transition_positions", "values": [[3.83], [3.83, 5.83]]},
                                   {"key": "train.speed_kmh", "values": [120, 160]}])
    out = tmp_path / "out"
    table = study.run_study(spec, str(out), workers=2, progress=False, plots=True)
    assert (table["status"] == "ok").all(), table["message"].tolist()
    assert set(table["overlap.support_rise"]) == {"eq. 6-8", "d 0.06"}
    assert set(table["droppers.transition_positions"]) == {"[3.83]", "[3.83, 5.83]"}
    row = table[(table["overlap.support_rise"] == "eq. 6-8") & (table["droppers.transition_positions"] == "[3.83]")
                & (table["train.speed_kmh"] == 160)].iloc[0]
    stats, _ = cs.run_pass(calpe, overrides={"output.analysis_spans": [2, 3], "droppers.transition_positions": [3.83],
                                             "train.speed_kmh": 160}, sample_rate=0)
    assert row["pantographs.0.std_force_N"] == stats["pantographs"][0]["std_force_N"]
    assert row["section_support_rises.0.last_m"] == stats["section_support_rises"][0]["last_m"]
    fixed = table[table["overlap.support_rise"] == "d 0.06"]
    assert (fixed["section_support_rises.0.last_m"] == 0.06).all()
    assert os.path.exists(str(out / "pantographs_0_std_force_N.png"))
    with pytest.raises(study.StudyError, match=r"parameters\[0\].labels"):
        study.load_study(write_study(str(tmp_path / "b.yaml"), sampling="grid",
                                     parameters=[{"key": "a", "values": [1, 2], "labels": ["one"]}]))


def test_a_study_links_a_report_per_case(tmp_path):
    # report: true: each case's pass files and report in DIR/cases/NNNNNN/, the path in results.csv
    # and a link in DIR/index.html; every linked page is a complete report (its sections and
    # pictures, as test_pass_report checks simulate_pass --report's). A short line keeps it quick.
    spec = write_study(str(tmp_path / "s.yaml"), sampling="grid", report=True,
                       overrides={"line.span_count": 6, "numerics.element_length": 0.5},
                       parameters=[{"key": "train.speed_kmh", "values": [200, 250]}])
    out = tmp_path / "out"
    table = study.run_study(spec, str(out), workers=2, progress=False, plots=False)
    assert (table["status"] == "ok").all(), table["message"].tolist()
    index = (out / "index.html").read_text()
    for rel in table["report"]:
        assert not os.path.isabs(rel)
        page = (out / rel).read_text()
        for section in ("force", "head", "uplift", "histogram", "psd", "droppers", "losses"):
            assert f"<h2 id='{section}'>" in page
            assert (out / os.path.dirname(rel) / f"report_{section}.png").read_bytes()[1:4] == b"PNG"
        assert f"href='{rel}'" in index
        # the case's own stats.json holds the outputs the table shows
        import json as _json
        stats = _json.loads((out / os.path.dirname(rel) / "stats.json").read_text())
        row = table[table["report"] == rel].iloc[0]
        assert stats["pantographs"][0]["std_force_N"] == row["pantographs.0.std_force_N"]
    with pytest.raises(study.StudyError, match="report"):
        study.load_study(write_study(str(tmp_path / "b.yaml"), report="yes", parameters=[{"key": "a", "values": [1]}]))


def test_a_study_file_is_read_whole(tmp_path):
    # An `overrides:` after 1 MiB of comments is part of the study, and a grid of 100,000 values
    # has 100,000 values (a reader that stops at a fixed size loses both without a word).
    path = tmp_path / "long.yaml"
    doc = yaml.safe_dump({"name": "t", "scene": REFERENCE, "outputs": ["pantographs.0.std_force_N"],
                          "parameters": [{"key": "train.speed_kmh", "values": list(range(100_000))}]})
    path.write_text(doc + "# " + "x" * 78 + "\n" * 1 + ("# " + "y" * 78 + "\n") * 14000
                    + "overrides: {numerics.preset: balanced}\n")
    assert path.stat().st_size > (1 << 20) + 100
    s = study.load_study(str(path))
    assert s["overrides"] == {"numerics.preset": "balanced"}
    assert len(s["parameters"][0]["values"]) == 100_000
    # beyond the stated bound: refused with the bound, not cut
    big = tmp_path / "big.yaml"
    with open(big, "w") as f:
        f.write("# " + "z" * 1000 + "\n")
        f.seek(study.MAX_STUDY_BYTES + 10)
        f.write("\n")
    with pytest.raises(study.StudyError, match="larger than"):
        study.load_study(str(big))


def test_a_key_given_twice_is_refused_by_name(tmp_path):
    path = tmp_path / "dup.yaml"
    path.write_text(f"name: t\nscene: {REFERENCE}\noutputs: [pantographs.0.std_force_N]\n"
                    "parameters:\n  - key: train.speed_kmh\n    values: [200, 250]\n    values: [300]\n")
    with pytest.raises(study.StudyError, match=r"line 7: key 'values' is given twice.*first on line 6"):
        study.load_study(str(path))
    path.write_text(f"name: t\nscene: {REFERENCE}\nseed: 1\nseed: 2\noutputs: [a]\n"
                    "parameters: [{key: a, values: [1]}]\n")
    with pytest.raises(study.StudyError, match="key 'seed' is given twice"):
        study.load_study(str(path))
    path.write_text(f"name: &a [*a]\nscene: {REFERENCE}\noutputs: [a]\nparameters: [{{key: a, values: [1]}}]\n")
    with pytest.raises(study.StudyError, match="alias"):
        study.load_study(str(path))


def test_a_plan_too_large_is_refused_before_it_is_made(tmp_path):
    # 10 parameters of 10 values: 1e10 cases, some terabytes of plan; refused from the counts.
    grid = [{"key": f"p{i}", "values": list(range(10))} for i in range(10)]
    with pytest.raises(study.StudyError, match=r"10000000000 cases.*at most 100000"):
        study.load_study(write_study(str(tmp_path / "g.yaml"), sampling="grid", parameters=grid))
    sampled = [{"key": f"p{i}", "distribution": {"type": "uniform", "low": 0, "high": 1}} for i in range(20)]
    with pytest.raises(study.StudyError, match=r"samples.*1000000 samples x \(20 parameters \+ 2\)"):
        study.load_study(write_study(str(tmp_path / "s.yaml"), sampling="saltelli", samples=1_000_000,
                                     parameters=sampled))


def run_cli_err(args, timeout=120):
    return subprocess.run([sys.executable, STUDY_CLI, *args, "--no-progress", "--no-plots"], capture_output=True,
                          text=True, timeout=timeout)


def test_a_damaged_output_directory_is_named_or_redone(tmp_path):
    # Cases that fail at once (a dt above the model's stability limit, refused by its build) keep
    # it quick; what is checked is the directory's handling, not the passes.
    spec = write_study(str(tmp_path / "s.yaml"), sampling="grid",
                       parameters=[{"key": "numerics.dt", "values": [0.01, 0.02]}])
    out = tmp_path / "out"
    r = run_cli_err([spec, "--out", str(out)], timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    # An emptied case file: that case runs again, with a word naming it.
    (out / "cases" / "000001.json").write_text("")
    r = run_cli_err([spec, "--out", str(out)], timeout=300)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stdout + r.stderr
    assert "000001.json" in r.stdout and "runs again" in r.stdout
    assert len(pd.read_csv(out / "results.csv")) == 2
    # A damaged plan.json: named, with what to do.
    (out / "plan.json").write_text('{"study": ')
    r = run_cli_err([spec, "--out", str(out)])
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert "plan.json" in r.stderr and "new --out" in r.stderr
    # A changed plan on the same --out: refused, saying what differs and what to do.
    (out / "plan.json").unlink()
    r = run_cli_err([spec, "--out", str(out)], timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    changed = write_study(str(tmp_path / "s2.yaml"), sampling="grid",
                          parameters=[{"key": "numerics.dt", "values": [0.01, 0.02, 0.03]}])
    r = run_cli_err([changed, "--out", str(out)])
    assert r.returncode == 2 and "'parameters' differs" in r.stderr and "new --out" in r.stderr, r.stderr


def test_a_bad_scheduler_address_is_named(tmp_path):
    spec = write_study(str(tmp_path / "s.yaml"), sampling="grid", parameters=[{"key": "train.speed_kmh",
                                                                             "values": [200]}])
    for address in ("not an address", "tcp://127.0.0.1:1"):
        r = run_cli_err([spec, "--out", str(tmp_path / "out"), "--scheduler", address], timeout=120)
        assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
        assert "--scheduler" in r.stderr and address in r.stderr
        assert not (tmp_path / "out").exists()
    # Nothing is made in a directory that was there either, and the directory stays.
    (tmp_path / "there").mkdir()
    with pytest.raises(study.StudyError, match="cannot reach a Dask scheduler"):
        study.run_study(spec, str(tmp_path / "there"), scheduler="tcp://127.0.0.1:1", progress=False, plots=False)
    assert os.listdir(tmp_path / "there") == []


def test_a_map_draws_a_grid_value_whose_cases_all_failed(tmp_path, monkeypatch):
    # The overlap study's rises [eq. 6-8, 0.15, 0.50] at two speeds, every 0.50 case failed: the
    # map keeps the 0.50 column, its cells hatched as failed, with a legend entry saying so.
    from matplotlib.patches import Rectangle
    from catenary_sim import study_plots
    s = {"name": "overlap", "sampling": "grid", "outputs": ["pantographs.0.std_force_N"],
         "parameters": [{"key": "overlap.support_rise", "values": [None, 0.15, 0.5], "labels": ["eq. 6-8", 0.15, 0.5]},
                        {"key": "train.speed_kmh", "values": [120, 160], "labels": [120, 160]}]}
    rows = []
    for rise in ["eq. 6-8", 0.15, 0.5]:
        for v in (120, 160):
            failed = rise == 0.5
            rows.append({"overlap.support_rise": rise, "train.speed_kmh": v,
                         "pantographs.0.std_force_N": math.nan if failed else 20.0 + v / 100,
                         "status": "failed" if failed else "ok", "message": "diverged" if failed else ""})
    figs = []
    monkeypatch.setattr(study_plots, "_save", lambda fig, path: figs.append(fig))
    study_plots.plot_study(s, pd.DataFrame(rows), str(tmp_path))
    ax = figs[0].axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["eq. 6-8", "0.15", "0.5"]
    hatched = [p for p in ax.patches if isinstance(p, Rectangle) and p.get_hatch()]
    assert sorted((p.get_x(), p.get_y()) for p in hatched) == [(2, 0), (2, 1)]
    legend = ax.get_legend()
    assert legend is not None and "failed" in legend.get_texts()[0].get_text()


def test_bad_arguments_are_refused_by_name(tmp_path):
    spec = write_study(str(tmp_path / "s.yaml"), parameters=[{"key": "train.speed_kmh", "values": [200]}])
    (tmp_path / "file").write_text("")
    for call, words in [
            (lambda: study.load_study(None), "path = None: allowed a file path"),
            (lambda: study.load_study(str(tmp_path / "none.yaml")), "none.yaml' cannot be read"),
            (lambda: study.run_study(None, str(tmp_path / "out")), "study_path = None: allowed a file path"),
            (lambda: study.run_study(spec, None), "out = None: allowed a file path"),
            (lambda: study.run_study(spec, str(tmp_path / "file")), "exists and is not a directory"),
            # a directory that cannot be made (/proc takes no new entries)
            (lambda: study.run_study(spec, "/proc/catenary_sim_out"), "--out /proc/catenary_sim_out: cannot be written"),
            # as calibrate: true is not one worker
            (lambda: study.run_study(spec, str(tmp_path / "out"), workers=True), "workers = True: allowed an integer"),
            (lambda: study.run_study(spec, str(tmp_path / "out"), workers=2.0), "workers = 2.0: allowed an integer")]:
        with pytest.raises(study.StudyError) as e:
            call()
        assert words in str(e.value)
    assert not (tmp_path / "out").exists()


def test_an_output_directory_whose_lock_cannot_be_opened_is_taken_away(tmp_path, monkeypatch):
    # The lock is opened after DIR and DIR/cases are made; a file system that then refuses the file
    # (full, a quota) must not leave the new, empty directories behind.
    spec = write_study(str(tmp_path / "s.yaml"), parameters=[{"key": "train.speed_kmh", "values": [200]}])
    real_open = open

    def refusing_open(path, *args, **kwargs):
        if str(path).endswith(".catenary_sim.lock"):
            raise OSError(28, "No space left on device")
        return real_open(path, *args, **kwargs)

    monkeypatch.setattr(study, "open", refusing_open, raising=False)
    out = tmp_path / "new" / "out"
    with pytest.raises(study.StudyError, match="cannot be written .No space left on device"):
        study.run_study(spec, str(out))
    assert not (tmp_path / "new").exists()  # nor the parent made for it
    # A directory that was there already keeps what it holds.
    kept = tmp_path / "kept"
    (kept / "cases").mkdir(parents=True)
    with pytest.raises(study.StudyError, match="cannot be written"):
        study.run_study(spec, str(kept))
    assert (kept / "cases").is_dir()
