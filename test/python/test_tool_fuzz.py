"""Damaged input to the Python tools (pass_report, fit_pantograph, catenary_sim_study): every
class of damage gives a non-zero exit with a message naming the file and the column, row or field,
no Python traceback, no signal, and no half-written output. Each class is one case below; a
class added to a tool gets its case here."""
import json
import os
import shutil
import stat
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEVEL = os.environ.get("CATENARY_SIM_DEVEL_LIB", os.path.join(ROOT, ".ws", "devel", "lib", "catenary_sim"))
PASS_REPORT = os.path.join(ROOT, "scripts", "pass_report")
FIT = os.path.join(ROOT, "scripts", "fit_pantograph")
STUDY = os.path.join(ROOT, "scripts", "catenary_sim_study")
REFERENCE = os.path.join(ROOT, "config", "reference_55m.yaml")


def run(args, timeout=120):
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=timeout)


def refused(r, *words):
    """Non-zero exit, not by a signal, no traceback, every word in the message."""
    assert r.returncode > 0, (r.returncode, r.stderr)
    assert "Traceback" not in r.stderr and "Traceback" not in r.stdout, r.stderr
    for w in words:
        assert w in r.stderr, (w, r.stderr)


# --------------------------------------------------------------------------------------------
# pass_report on damaged output directories
# --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def passes(tmp_path_factory):
    """Two short passes of six 55 m spans (as test_pass_report): the 2-D line and the 3-D one
    (stagger and a steady 20 m/s cross wind, so that there is blow-off to draw), whose lateral files
    the report draws too."""
    base = tmp_path_factory.mktemp("passes")
    out = {}
    for name, extra in (("2d", []), ("3d", ["--set", "stagger.contact_wire=[0.3,-0.3]", "--set", "wind.speed=20"])):
        d = str(base / name)
        r = subprocess.run([os.path.join(DEVEL, "simulate_pass"), "--scene", REFERENCE, "--out", d, "--speed", "250",
                            "--set", "line.span_count=6", "--set", "numerics.element_length=0.5", "--no-progress",
                            *extra], capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr
        out[name] = d
    return out


def set_cell(path, column, value, row=1):
    lines = open(path).read().splitlines()
    head = lines[0].split(",")
    cells = lines[row].split(",")
    cells[head.index(column)] = value
    lines[row] = ",".join(cells)
    open(path, "w").write("\n".join(lines) + "\n")


def header_only(path):
    with open(path) as f:
        head = f.readline()
    with open(path, "w") as f:
        f.write(head)


def binary(path):
    open(path, "wb").write(bytes(range(256)) * 64)


def with_nul(path):
    text = open(path).read().splitlines()
    text[1] = text[1][:3] + "\0" + text[1][3:]
    open(path, "w").write("\n".join(text) + "\n")


def short_row(path):
    lines = open(path).read().splitlines()
    lines[2] = lines[2].rsplit(",", 1)[0]
    open(path, "w").write("\n".join(lines) + "\n")


def renamed_column(column):
    def damage(path):
        lines = open(path).read().splitlines()
        lines[0] = lines[0].replace(column, "x" + column, 1)
        open(path, "w").write("\n".join(lines) + "\n")
    return damage


def cell(column, value, row=1):
    return lambda path: set_cell(path, column, value, row)


def added_row(text):
    return lambda path: open(path, "a").write(text + "\n")


def stats_field(edit):
    def damage(path):
        d = json.load(open(path))
        edit(d)
        json.dump(d, open(path, "w"))
    return damage


def assign(keys, value):
    def edit(d):
        node = d
        for k in keys[:-1]:
            node = node[k]
        node[keys[-1]] = value
    return edit


# (id, pass, file, damage, words the message must hold)
REPORT_CASES = [
    ("timeseries header only", "2d", "timeseries.csv", header_only, ["timeseries.csv", "0 data rows"]),
    ("timeseries binary", "2d", "timeseries.csv", binary, ["timeseries.csv", "not a text CSV"]),
    ("timeseries NUL", "2d", "timeseries.csv", with_nul, ["timeseries.csv"]),
    ("timeseries short row", "2d", "timeseries.csv", short_row, ["timeseries.csv line 3"]),
    ("timeseries 1e308 force", "2d", "timeseries.csv", cell("leading_force_N", "1e308", 40),
     ["timeseries.csv line 41", "leading_force_N", "1e308"]),
    ("timeseries -1e308 position", "2d", "timeseries.csv", cell("leading_position_m", "-1e308"),
     ["timeseries.csv line 2", "leading_position_m"]),
    ("timeseries inf", "2d", "timeseries.csv", cell("leading_force_N", "inf"), ["leading_force_N", "inf"]),
    ("timeseries nan position", "2d", "timeseries.csv", cell("leading_position_m", "nan"),
     ["leading_position_m", "finite"]),
    ("timeseries text", "2d", "timeseries.csv", cell("uplift_steady_arm1_m", "abc"),
     ["timeseries.csv line 2", "uplift_steady_arm1_m", "'abc' is not a number"]),
    ("timeseries no position column", "2d", "timeseries.csv", renamed_column("leading_position_m"),
     ["timeseries.csv", "no column 'leading_position_m'"]),
    ("processed header only", "2d", "force_processed.csv", header_only, ["force_processed.csv", "0 data rows"]),
    ("processed 1e308", "2d", "force_processed.csv", cell("leading_force_filtered_N", "1e308"),
     ["force_processed.csv line 2", "leading_force_filtered_N"]),
    ("psd header only", "2d", "psd.csv", header_only, ["psd.csv", "0 data rows"]),
    ("psd garbage", "2d", "psd.csv", cell("psd_N2_per_hz", "#@!"), ["psd.csv line 2", "psd_N2_per_hz"]),
    ("psd 1e308", "2d", "psd.csv", cell("frequency_hz", "1e308"), ["psd.csv line 2", "frequency_hz"]),
    ("psd no pantograph column", "2d", "psd.csv", renamed_column("pantograph"), ["psd.csv", "'pantograph'"]),
    ("psd binary", "2d", "psd.csv", binary, ["psd.csv"]),
    ("droppers garbage", "2d", "droppers.csv", cell("max_force_N", "lots"), ["droppers.csv line 2", "max_force_N"]),
    ("droppers 1e308", "2d", "droppers.csv", cell("station_m", "1e308"), ["droppers.csv line 2", "station_m"]),
    ("droppers no station", "2d", "droppers.csv", renamed_column("station_m"), ["droppers.csv", "'station_m'"]),
    ("rainflow garbage", "2d", "dropper_rainflow.csv", cell("cycles", "x"), ["dropper_rainflow.csv line 2", "cycles"]),
    ("losses garbage row", "2d", "contact_losses.csv", added_row("leading,abc,1,0.01,0.5"),
     ["contact_losses.csv line 2", "start_time_s"]),
    ("stats binary", "2d", "stats.json", binary, ["stats.json"]),
    ("stats cut", "2d", "stats.json", lambda p: os.truncate(p, 200), ["stats.json"]),
    ("stats not a map", "2d", "stats.json", lambda p: open(p, "w").write("[1, 2]"), ["stats.json", "a JSON map"]),
    ("stats null cutoff", "2d", "stats.json", stats_field(assign(["filter_cutoff_hz"], None)),
     ["stats.json", "filter_cutoff_hz", "null"]),
    ("stats null section", "2d", "stats.json", stats_field(assign(["analysis_section_m"], None)),
     ["stats.json", "analysis_section_m"]),
    ("stats null in section", "2d", "stats.json", stats_field(assign(["analysis_section_m", 1], None)),
     ["stats.json", "analysis_section_m[1]"]),
    ("stats null pantograph name", "2d", "stats.json", stats_field(assign(["pantographs", 0, "name"], None)),
     ["stats.json", "pantographs[0].name"]),
    ("stats null spectrum", "2d", "stats.json", stats_field(assign(["pantographs", 0, "spectrum"], None)),
     ["stats.json", "pantographs[0].spectrum"]),
    ("stats null peak", "2d", "stats.json",
     stats_field(assign(["pantographs", 0, "spectrum", "peaks", 0, "frequency_hz"], None)),
     ["stats.json", "pantographs[0].spectrum.peaks[0].frequency_hz"]),
    ("stats null unfiltered", "2d", "stats.json",
     stats_field(assign(["pantographs", 0, "contact_loss_events", "count"], None)),
     ["stats.json", "pantographs[0].contact_loss_events.count"]),
    ("stats text arm", "2d", "stats.json", stats_field(assign(["steady_arms", 0, "max_uplift_m"], "high")),
     ["stats.json", "steady_arms[0].max_uplift_m"]),
    ("stats 1e308 mean", "2d", "stats.json", stats_field(assign(["pantographs", 0, "mean_force_N"], 1e308)),
     ["stats.json", "pantographs[0].mean_force_N"]),
    ("stats NaN support", "2d", "stats.json", stats_field(assign(["support_stations_m", 0], float("nan"))),
     ["stats.json", "support_stations_m[0]"]),
    ("stats no pantographs", "2d", "stats.json", stats_field(assign(["pantographs"], [])),
     ["stats.json", "pantographs"]),
    ("stats reversed section", "2d", "stats.json", stats_field(assign(["analysis_section_m"], [220.0, 110.0])),
     ["stats.json", "analysis_section_m"]),
    ("lateral histogram garbage", "3d", "lateral_histogram.csv", cell("collector", "first"),
     ["lateral_histogram.csv line 2", "collector"]),
    ("lateral histogram 1e308", "3d", "lateral_histogram.csv", cell("percent_of_contact_time", "1e308"),
     ["lateral_histogram.csv line 2", "percent_of_contact_time"]),
    ("lateral histogram header only", "3d", "lateral_histogram.csv", renamed_column("pantograph"),
     ["lateral_histogram.csv", "'pantograph'"]),
    ("lateral 1e308", "3d", "lateral.csv", cell("leading_lateral_m", "1e308"), ["lateral.csv line 2"]),
    ("blow-off garbage", "3d", "blow_off.csv", cell("span", "one"), ["blow_off.csv line 2", "span"]),
    ("lateral stats null", "3d", "stats.json", stats_field(assign(["lateral", "working_width_m"], None)),
     ["stats.json", "lateral.working_width_m"]),
    ("lateral file missing", "3d", "blow_off.csv", os.remove, ["blow_off.csv is missing"]),
]


@pytest.mark.parametrize("name,which,filename,damage,words", REPORT_CASES, ids=[c[0] for c in REPORT_CASES])
def test_pass_report_names_damaged_input(passes, tmp_path, name, which, filename, damage, words):
    d = str(tmp_path / "out")
    shutil.copytree(passes[which], d)
    damage(os.path.join(d, filename))
    r = run([PASS_REPORT, d], timeout=300)
    refused(r, *words)
    assert not os.path.exists(os.path.join(d, "report.html"))  # nothing half written
    assert not [n for n in os.listdir(d) if n.startswith("report_")]


def test_pass_report_html_targets(passes, tmp_path):
    d = str(tmp_path / "out")
    shutil.copytree(passes["2d"], d)
    # A path under /proc cannot be written: named, not a traceback.
    r = run([PASS_REPORT, d, "--html", "/proc/catenary_sim_report.html"], timeout=300)
    refused(r, "/proc/catenary_sim_report.html")
    # A directory: refused, left as it is.
    os.mkdir(os.path.join(d, "page"))
    r = run([PASS_REPORT, d, "--html", os.path.join(d, "page")], timeout=300)
    refused(r, "page", "directory")
    assert os.path.isdir(os.path.join(d, "page"))
    # A character device is written through, never renamed over (as root /dev/null would become a file).
    r = run([PASS_REPORT, d, "--html", "/dev/null", "--quiet"], timeout=300)
    assert r.returncode == 0, r.stderr
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    # A pipe too: its reader gets the page.
    fifo = os.path.join(d, "pipe")
    os.mkfifo(fifo)
    p = subprocess.Popen([sys.executable, PASS_REPORT, d, "--html", fifo, "--quiet"], stderr=subprocess.PIPE, text=True)
    with open(fifo, "rb") as f:
        page = f.read()
    assert p.wait(timeout=300) == 0, p.stderr.read()
    assert page.startswith(b"<!DOCTYPE html>") and page.rstrip().endswith(b"</html>")
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)


def test_pass_report_refuses_a_directory_that_is_not_one(tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    refused(run([PASS_REPORT, str(f)]), str(f), "not a directory")


# --------------------------------------------------------------------------------------------
# fit_pantograph on damaged FRF files and bad arguments
# --------------------------------------------------------------------------------------------
def good_frf(path, n=40):
    from catenary_sim.pantograph_fit import chain_receptance
    f = np.geomspace(0.5, 20.0, n)
    h = chain_receptance(f, [7.2, 15.0], [4200.0, 50.0], [10.0, 100.0])
    pd.DataFrame({"frequency_hz": f, "receptance_re_m_per_n": h.real, "receptance_im_m_per_n": h.imag}).to_csv(
        path, index=False)
    return path


def frf_cell(column, value, row=1):
    return lambda path: set_cell(path, column, value, row)


FIT_CASES = [
    ("empty", lambda p: open(p, "w").close(), ["frf.csv", "empty"]),
    ("header only", header_only, ["frf.csv", "no data rows"]),
    ("binary", binary, ["frf.csv", "not a text CSV"]),
    ("NUL", with_nul, ["frf.csv"]),
    ("NaN row", frf_cell("receptance_re_m_per_n", "nan", 6), ["frf.csv", "data row 6", "receptance_re_m_per_n"]),
    ("empty cell", frf_cell("receptance_im_m_per_n", "", 3), ["frf.csv", "data row 3", "receptance_im_m_per_n"]),
    ("text cell", frf_cell("frequency_hz", "ten", 2), ["frf.csv", "data row 2", "frequency_hz"]),
    ("inf cell", frf_cell("frequency_hz", "inf", 2), ["frf.csv", "data row 2", "frequency_hz"]),
    ("1e308 frequency", frf_cell("frequency_hz", "1e308", 2), ["data row 2", "frequency_hz", "<= 10000 Hz"]),
    ("negative frequency", frf_cell("frequency_hz", "-1", 2), ["data row 2", "frequency_hz", "> 0"]),
    ("short row", short_row, ["frf.csv"]),
    ("wrong columns", renamed_column("frequency_hz"), ["frf.csv", "frequency_hz"]),
    ("one frequency", lambda p: pd.read_csv(p).iloc[[3] * 12].to_csv(p, index=False),
     ["1 distinct frequency", "12 rows", "at least 7 distinct"]),
    ("too many rows", lambda p: good_frf(p, 240_000), ["frf.csv", "at most 20000"]),
    ("a directory", lambda p: (os.remove(p), os.mkdir(p)), ["frf.csv", "directory"]),
    ("missing", os.remove, ["frf.csv"]),
]


@pytest.mark.parametrize("name,damage,words", FIT_CASES, ids=[c[0] for c in FIT_CASES])
def test_fit_pantograph_names_damaged_input(tmp_path, name, damage, words):
    path = good_frf(str(tmp_path / "frf.csv"))
    damage(path)
    out = tmp_path / "out"
    r = run([FIT, path, "--out", str(out)], timeout=120)
    refused(r, *words)
    assert not (out / "pantograph_fit.yaml").exists() and not (out / "fit_residual.csv").exists()


@pytest.mark.parametrize("args,words", [
    (["--out", "{tmp}/file"], ["--out", "not a directory"]),
    (["--out", "/proc/catenary_sim_fit"], ["--out", "/proc/catenary_sim_fit"]),
    (["--out", "{tmp}/o", "--fmin", "100"], ["--fmin 100"]),
    (["--out", "{tmp}/o", "--fmin", "5", "--fmax", "1"], ["--fmin", "--fmax"]),
    (["--out", "{tmp}/o", "--name", ""], ["--name"]),
    (["--out", "{tmp}/o", "--static-uplift", "nan"], ["--static-uplift"]),
], ids=["out is a file", "out under proc", "no frequency in band", "band reversed", "empty name", "nan uplift"])
def test_fit_pantograph_names_bad_arguments(tmp_path, args, words):
    path = good_frf(str(tmp_path / "frf.csv"))
    (tmp_path / "file").write_text("x")
    r = run([FIT, path, *[a.replace("{tmp}", str(tmp_path)) for a in args]], timeout=120)
    refused(r, *words)


# --------------------------------------------------------------------------------------------
# catenary_sim_study on damaged study files (refused before any case runs)
# --------------------------------------------------------------------------------------------
GOOD_STUDY = {"name": "t", "scene": REFERENCE, "sampling": "grid", "outputs": ["pantographs.0.std_force_N"],
              "parameters": [{"key": "train.speed_kmh", "values": [200, 250]}]}


def study_text(**changes):
    d = dict(GOOD_STUDY)
    d.update(changes)
    return yaml.safe_dump(d)


STUDY_CASES = [
    ("empty", "", ["s.yaml", "a map of fields"]),
    ("binary", bytes(range(256)) * 8, ["s.yaml", "not UTF-8"]),
    ("not YAML", "name: [unclosed\n", ["s.yaml", "not valid YAML"]),
    ("a list", "- 1\n- 2\n", ["s.yaml", "a map of fields"]),
    ("duplicate top key", study_text() + "seed: 1\nseed: 2\n", ["s.yaml", "key 'seed' is given twice"]),
    ("duplicate nested key", study_text().replace("- key: train.speed_kmh", "- key: train.speed_kmh\n  key: x"),
     ["s.yaml", "key 'key' is given twice"]),
    ("self alias", "name: &a [*a]\n" + study_text().split("\n", 1)[1], ["s.yaml", "alias"]),
    ("alias bomb", "a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1]\nb: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a]\n"
     "c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b]\n", ["s.yaml", "alias"]),
    ("unknown field", study_text(spam=1), ["'spam'"]),
    ("missing scene", study_text(scene="nowhere.yaml"), ["'scene'", "nowhere.yaml"]),
    ("grid too large", study_text(parameters=[{"key": f"p{i}", "values": list(range(10))} for i in range(8)]),
     ["'parameters'", "100000000 cases"]),
    ("samples too many", study_text(sampling="saltelli", samples=1_000_000,
                                    parameters=[{"key": f"p{i}", "distribution": {"type": "uniform", "low": 0,
                                                                                   "high": 1}} for i in range(5)]),
     ["'samples'", "7000000 cases"]),
    ("nan value", study_text().replace("- 250", "- .nan"), ["'parameters[0].values'", "finite"]),
    ("inf in a list value", study_text().replace("- 250", "- [1.0, .inf]"), ["'parameters[0].values'", "finite"]),
    ("scene a directory", study_text(scene=os.path.dirname(REFERENCE)), ["'scene'", "is a directory"]),
    ("a date", study_text().replace("- 250", "- 2024-01-01"), ["s.yaml", "plan.json"]),
    ("deep nesting", "name: " + "[" * 5000 + "]" * 5000 + "\n", ["s.yaml"]),
]


@pytest.mark.parametrize("name,text,words", STUDY_CASES, ids=[c[0] for c in STUDY_CASES])
def test_study_names_damaged_study_files(tmp_path, name, text, words):
    path = tmp_path / "s.yaml"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    r = run([STUDY, str(path), "--out", str(tmp_path / "out"), "--no-progress", "--no-plots"], timeout=120)
    refused(r, *words)
    assert not (tmp_path / "out" / "results.csv").exists()


def test_study_names_a_missing_study_file(tmp_path):
    r = run([STUDY, str(tmp_path / "none.yaml"), "--out", str(tmp_path / "out"), "--no-progress"], timeout=120)
    refused(r, "none.yaml", "No such file")


def load_pass_report():
    import importlib.machinery
    import importlib.util
    loader = importlib.machinery.SourceFileLoader("pass_report", PASS_REPORT)
    spec = importlib.util.spec_from_loader("pass_report", loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def test_pass_report_says_how_the_spectrum_was_averaged_and_counts_spans_from_one(passes, monkeypatch):
    # Two analysis spans of 55 m at 250 km/h are 1.6 s, less than one segment of 8 span-passing
    # periods: stats.json says 1 segment, and the title must not call a single periodogram
    # "Welch". blow_off.csv counts spans from 0, the viewer's heads-up from 1: the page as the
    # heads-up, the line's first span at 1.
    pr = load_pass_report()
    figs = []
    monkeypatch.setattr(pr, "fig_png", lambda fig: figs.append(fig) or b"")
    stats = pr.read_stats(os.path.join(passes["3d"], "stats.json"))
    assert [p["spectrum"]["segments"] for p in stats["pantographs"]] == [1]
    d = passes["3d"]
    cols = {n: pr.read_csv(os.path.join(d, n)) for n in ("timeseries.csv", "force_processed.csv", "contact_losses.csv",
                                                          "droppers.csv", "dropper_rainflow.csv", "psd.csv")}
    pr.build(stats, cols["timeseries.csv"], "t", cols["force_processed.csv"], "p", cols["contact_losses.csv"], "l",
             cols["droppers.csv"], "d", cols["dropper_rainflow.csv"], "r", cols["psd.csv"], "f")
    psd_title = figs[4].axes[0].get_title()
    assert "Welch" not in psd_title and "single" in psd_title
    pr.build_lateral(stats, d)
    blow = figs[-1].axes[2]
    first_span_bars = sorted(p.get_x() + p.get_width() / 2 for p in blow.patches)[:2]
    assert first_span_bars == pytest.approx([0.8, 1.2])
    assert "first span is 1" in blow.get_xlabel()


def test_a_pass_sampling_too_little_of_the_analysis_section(tmp_path):
    # A train ending exactly where the analysis section starts runs none of it: refused by
    # train.end. A millimetre further, the pantograph is sampled there once: no speed through the
    # section, so no spectrum and no passing frequencies; the summary and the report say so
    # instead of printing NaN or refusing the pass's own files.
    sim = os.path.join(DEVEL, "simulate_pass")
    common = ["--scene", REFERENCE, "--set", "line.span_count=6", "--set", "numerics.preset=fast", "--no-progress"]
    first = 2 * 55.0  # output.analysis_spans of the reference scene start at its third support
    r = subprocess.run([sim, *common, "--out", str(tmp_path / "a"), "--set", "train.end=%g" % first],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode > 0 and "train.end" in r.stderr and "allowed >" in r.stderr, r.stderr
    assert not os.path.exists(tmp_path / "a" / "stats.json")
    r = subprocess.run([sim, *common, "--out", str(tmp_path / "b"), "--set", "train.end=%g" % (first + 0.001), "--report"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "span passing unknown" in r.stdout and "nan" not in r.stdout.lower(), r.stdout
    assert os.path.exists(tmp_path / "b" / "report_psd.png")
