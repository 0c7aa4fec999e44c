"""Measured records (catenary_sim.measurement, scripts/compare_measurement): a record made from the
model's own pass compares with zero deviation to the CSV's rounding; the one Python statistics
function agrees with the core's stats.json on the simulated side; a synthesised record's statistics
stay within bounds derived from the noise added; each class of bad record is refused by name with
its column and line; the CLI writes its report and refuses bad input without writing anything."""
import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest
import yaml

import catenary_sim as cs
from catenary_sim import measurement as cm

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
REFERENCE = os.path.join(ROOT, "config", "reference_55m.yaml")
CLI = os.path.join(ROOT, "scripts", "compare_measurement")
# Six 55 m spans with 0.5 m elements: a pass of a second or two, analysis section 110-220 m.
SHORT = ["line.span_count=6", "numerics.element_length=0.5"]
RAMP = ([0.0, 330.0], [230.0, 270.0])  # km/h rising along the line: a speed profile, not one speed


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("clean") / "run.csv")
    return cm.synthesise_record(REFERENCE, path, overrides=SHORT, speed_profile=RAMP, sample_rate_hz=200.0,
                                bandwidth_hz=20.0)


def filter_gain(fs, fc, n=4096):
    """The l1 norm of the zero-phase low-pass's impulse response: the most a filtered series can
    move per unit change of the series anywhere (sup norm)."""
    x = np.zeros(n)
    x[n // 2] = 1.0
    return float(np.sum(np.abs(cm.lowpass(x, fs, fc))))


def test_a_record_of_the_models_own_pass_compares_with_zero_deviation(clean):
    c = cm.compare(REFERENCE, clean, overrides=SHORT)
    assert c.settings["speed_profile"] == "the record's speed column"
    # The CSV's rounding: forces to 1e-4 N, stations to 1e-6 m (a station off by e moves the
    # simulated force by e |dF/dx|), uplift and head to 1e-4 mm. Each row's force differs by at
    # most half a unit of both; the filter moves a sup-norm difference by at most its l1 gain.
    rec = clean.force_N["leading"]
    slope = np.max(np.abs(np.diff(rec) / np.diff(clean.station_m)))
    row_bound = 0.5e-4 + 0.5e-6 * slope
    bound = filter_gain(200.0, c.settings["cutoff_hz"]) * row_bound
    assert bound < 1e-3  # the rounding is fine enough to make the identity a strict check
    rows = {(r["quantity"], r["of"]): r for r in c.rows}
    for name in ("mean_force_N", "std_force_N", "max_force_N", "min_force_N"):
        assert abs(rows[(name, "leading")]["deviation"]) <= bound, name
    for name in ("stat_max_force_N", "stat_min_force_N"):  # mean +- 3 std
        assert abs(rows[(name, "leading")]["deviation"]) <= 4 * bound, name
    assert rows[("force_max_abs_difference_N", "leading")]["simulated"] <= bound
    assert rows[("contact_loss_percent", "leading")]["deviation"] == 0.0
    # Uplift and head in mm to 1e-4: half that in m, and the station's share as for the force.
    for (q, owner), r in rows.items():
        if q == "max_uplift_m":
            u = clean.uplift_m[owner]
            du = np.max(np.abs(np.diff(u) / np.diff(clean.station_m)))
            assert abs(r["deviation"]) <= 0.5e-7 + 0.5e-6 * du, owner
    assert sum(q == "max_uplift_m" for q, _ in rows) == 3  # the steady arms at 110, 165 and 220 m
    h = clean.head_m["leading"]
    dh = np.max(np.abs(np.diff(h) / np.diff(clean.station_m)))
    assert abs(rows[("head_std_m", "leading")]["deviation"]) <= 0.5e-7 + 0.5e-6 * dh


def test_the_python_statistics_agree_with_the_cores_stats_json():
    # One function computes both sides' statistics: on the simulated pass at every step, with the
    # core's cutoff, it must give stats.json's figures. Both filters are the same 4th-order
    # bilinear Butterworth run forward and backward from the steady state with the same odd
    # padding (zero_phase_filter.cpp, scipy's sosfiltfilt): they differ by the rounding of the
    # coefficients and of the sums, about 1e-13 of the force; 1e-9 relative leaves room.
    run = cm.simulate_run(REFERENCE, None, SHORT, 280.0)
    core = run.stats["pantographs"][0]
    raw = run.force_N["leading"]
    x = run.position_m["leading"]
    a0, a1 = run.stats["analysis_section_m"]
    inside = (x >= a0) & (x <= a1)
    assert inside.sum() == core["samples"]
    filtered = cm.lowpass(raw, 1.0 / run.dt, run.stats["filter_cutoff_hz"])
    ours = cm.section_statistics(filtered, inside, loss_force=raw)
    for name in ("mean_force_N", "std_force_N", "stat_max_force_N", "stat_min_force_N", "max_force_N", "min_force_N"):
        assert ours[name] == pytest.approx(core[name], rel=1e-9, abs=1e-9), name
    assert ours["contact_loss_percent"] == core["contact_loss_percent"]
    unfiltered = cm.section_statistics(raw, inside)
    assert unfiltered["max_force_N"] == core["unfiltered"]["max_force_N"]
    # The largest steady-arm uplift: every arm in the section while the pantograph is within half
    # a span (55 m spans) of it, as the core takes it, from the same every-step series.
    worst = max(np.max(u[np.abs(x - xs) <= 27.5]) for xs, u in run.uplift_m if a0 - 1e-6 <= xs <= a1 + 1e-6)
    assert worst == core["max_uplift_at_support_m"]


def test_a_synthesised_records_statistics_differ_from_the_simulation_by_its_noise(tmp_path):
    # The comparison's cutoff above the measuring chain's bandwidth, so that the record's noise
    # shows whether the chain's filter was applied to it (unfiltered it would be 1.6 times larger).
    sigma, fs, bw, fc = 8.0, 1000.0, 40.0, 100.0
    rec = cm.synthesise_record(REFERENCE, str(tmp_path / "noisy.csv"), overrides=SHORT, speed_profile=250.0,
                               sample_rate_hz=fs, bandwidth_hz=bw, noise_std_N=sigma, seed=7)
    c = cm.compare(REFERENCE, rec, overrides=SHORT, cutoff_hz=fc)
    n = c.settings["rows_in_section"]
    # White noise of sigma per sample through the measuring filter and the comparison's filter
    # (both zero phase): its std in the compared force is sigma_f (from the filters' gains).
    sigma_f = cm.noise_after_filters(sigma, fs, [bw, fc])
    rows = {r["quantity"]: r for r in c.rows if r["of"] == "leading"}
    # The mean of the noise: the filters pass DC whole, so it is the mean of n white samples,
    # std sigma / sqrt(n); 5 of them is a chance of 6e-7.
    assert abs(rows["mean_force_N"]["deviation"]) <= 5 * sigma / math.sqrt(n)
    # std is a norm of the de-meaned series: |std(s + e) - std(s)| <= std(e), and std(e) is sigma_f
    # within a few per cent over ~2 x 40 Hz x 1.6 s independent values; 1.5 sigma_f is far beyond.
    assert abs(rows["std_force_N"]["deviation"]) <= 1.5 * sigma_f
    # max(s + e) - max(s) and min likewise are at most max |e|: 6 sigma_f over a thousand samples
    # of a Gaussian is a chance below 1e-6.
    for name in ("max_force_N", "min_force_N"):
        assert abs(rows[name]["deviation"]) <= 6 * sigma_f, name
    for name in ("stat_max_force_N", "stat_min_force_N"):
        assert abs(rows[name]["deviation"]) <= 5 * sigma / math.sqrt(n) + 3 * 1.5 * sigma_f, name
    # And the noise is there, as large as the filters make it: over the whole record (4.75 s, about
    # 2 x 40 Hz x 4.75 s = 380 independent values) the rms difference of the two sides is sigma_f
    # with a sampling error of 1 / sqrt(2 x 380) = 3.6 %; 15 % is four of them.
    s = c.series
    diff = s["record_force_leading_filtered_N"] - s["simulated_force_leading_filtered_N"]
    assert float(np.sqrt(np.mean(diff ** 2))) == pytest.approx(sigma_f, rel=0.15)
    assert sigma_f > 1.0  # a noise that shows beside the CSV's rounding


# --------------------------------------------------------------------------------------------
# Bad records, each class by name
# --------------------------------------------------------------------------------------------
def write(tmp_path, clean, edit_rows=None, header=None, meta=None, name="bad.csv"):
    """A copy of the clean record with its lines edited: edit_rows {data row k: function(fields)}."""
    with open(clean.path) as f:
        lines = f.read().splitlines()
    head = lines[0].split(",")
    rows = [ln.split(",") for ln in lines[1:]]
    for k, fn in (edit_rows or {}).items():
        rows[k] = fn(rows[k], head)
    if header:
        head = header(head)
    out = tmp_path / name
    out.write_text("\n".join([",".join(head)] + [",".join(r) for r in rows if r is not None]) + "\n")
    with open(os.path.splitext(clean.path)[0] + ".yaml") as f:
        doc = yaml.safe_load(f)
    if meta:
        meta(doc)
    (tmp_path / (os.path.splitext(name)[0] + ".yaml")).write_text(yaml.safe_dump(doc))
    return str(out)


def setcol(col, value):
    def fn(r, head):
        r[head.index(col)] = value
        return r
    return fn


def refused(path, kind, field, row=None, scene=False):
    with pytest.raises(cm.RecordError) as e:
        if scene:
            cm.compare(REFERENCE, path, overrides=SHORT)
        else:
            cm.read_record(path)
    err = e.value
    assert err.kind == kind, str(err)
    assert err.field == field, str(err)
    assert err.row == row, str(err)
    assert kind in str(err) and field in str(err)
    return err


def test_nan_and_empty_cells_are_refused_with_their_line(tmp_path, clean):
    # data row k is line k + 2 (the header is line 1)
    refused(write(tmp_path, clean, {10: setcol("force_leading_N", "nan")}), "nan", "force_leading_N", 12)
    refused(write(tmp_path, clean, {20: setcol("speed_kmh", "")}), "nan", "speed_kmh", 22)
    refused(write(tmp_path, clean, {5: setcol("head_leading_mm", "1.2.3")}), "nan", "head_leading_mm", 7)


def test_gaps_and_stations_going_back_are_refused(tmp_path, clean):
    drop = lambda r, h: None  # noqa: E731
    # Rows 50 and 51 missing: row 52 (line 52 once they are gone) is 3 sample intervals after 49.
    refused(write(tmp_path, clean, {50: drop, 51: drop}), "gap", "time_s", 52)
    def back(r, h):
        r[h.index("station_m")] = "%.6f" % (float(r[h.index("station_m")]) - 1.0)
        return r
    refused(write(tmp_path, clean, {30: back}), "non_monotonic", "station_m", 32)


def test_wrong_and_unknown_units_are_refused(tmp_path, clean):
    refused(write(tmp_path, clean, header=lambda h: [c.replace("force_leading_N", "force_leading_lbf") for c in h]),
            "unknown_unit", "force_leading_lbf")
    refused(write(tmp_path, clean, header=lambda h: h[:-1] + ["temperature_C"]), "unknown_column", "temperature_C")
    # A force in kN under a column in N: a mean of 0.1 N is no contact force.
    def kn(r, h):
        k = h.index("force_leading_N")
        r[k] = "%.7f" % (float(r[k]) / 1000)
        return r
    with open(clean.path) as f:
        n = len(f.read().splitlines()) - 1
    refused(write(tmp_path, clean, {k: kn for k in range(n)}), "wrong_unit", "force_leading_N")
    # A speed in m/s under a column in km/h: the stations advance 3.6 times faster than it says.
    def mps(r, h):
        k = h.index("speed_kmh")
        r[k] = "%.6f" % (float(r[k]) / 3.6)
        return r
    refused(write(tmp_path, clean, {k: mps for k in range(n)}), "wrong_unit", "speed_kmh")
    # A force beyond 5 kN (N written under kN) on one row, named with its line.
    refused(write(tmp_path, clean, {40: setcol("force_leading_N", "9000")}), "wrong_unit", "force_leading_N", 42)


def test_bad_metadata_is_refused_by_field(tmp_path, clean):
    refused(write(tmp_path, clean, meta=lambda d: d.pop("sample_rate_hz")), "metadata", "sample_rate_hz")
    refused(write(tmp_path, clean, meta=lambda d: d.update(bandwith_hz=20)), "metadata", "bandwith_hz")
    refused(write(tmp_path, clean, meta=lambda d: d.update(sample_rate_hz=1000.0)), "wrong_unit", "time_s")
    refused(write(tmp_path, clean, {3: setcol("speed_kmh", "0")}), "speed_profile", "speed_kmh", 5)
    # YAML reads an unquoted support name 2 as a number: said so, not "no such support".
    err = refused(write(tmp_path, clean, meta=lambda d: d["supports"].update({2: 12.5})), "metadata", "supports.2")
    assert "in quotes" in err.allowed, str(err)


def test_what_the_scene_lacks_is_refused_by_name(tmp_path, clean):
    renamed = write(tmp_path, clean, header=lambda h: [c.replace("_leading_", "_trailing_") for c in h],
                    meta=lambda d: d.update(pantographs=["trailing"], station_of="trailing"), name="p.csv")
    err = refused(renamed, "unknown_pantograph", "force_trailing_N", scene=True)
    assert "leading" in err.allowed
    refused(write(tmp_path, clean, meta=lambda d: d.update(section_m=[200.0, 900.0]), name="s.csv"),
            "section_outside_line", "section_m", scene=True)
    refused(write(tmp_path, clean, meta=lambda d: d["supports"].update(A2=112.5), name="a.csv"),
            "unknown_support", "supports.A2", scene=True)


# --------------------------------------------------------------------------------------------
# The command line
# --------------------------------------------------------------------------------------------
def cli(*args):
    return subprocess.run([sys.executable, CLI] + [str(a) for a in args], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, timeout=600)


def test_the_cli_writes_its_report_and_marks_the_tolerances(tmp_path, clean):
    out = tmp_path / "cmp"
    r = cli(REFERENCE, clean.path, "--out", out, "--set", SHORT[0], "--set", SHORT[1], "--tolerance",
            "std_force_N=10%", "--tolerance", "leading.max_force_N=0", "--strict")
    # max_force_N = 0 N cannot hold to rounding: --strict exits 1, everything is written
    assert r.returncode == 1, r.stderr
    page = (out / "report.html").read_text()
    assert "id='statistics'" in page and "OUTSIDE" in page and "within" in page
    for name in ("force", "spectrum", "uplift", "speed"):
        assert (out / f"report_{name}.png").stat().st_size > 1000
    summary = json.loads((out / "comparison.json").read_text())
    assert summary["within"] is False
    assert summary["settings"]["tolerances"] == {"std_force_N": "10%", "leading.max_force_N": 0.0}
    assert (out / "simulated" / "stats.json").is_file()


def test_the_cli_refuses_bad_input_and_writes_nothing(tmp_path, clean):
    bad = write(tmp_path, clean, {10: setcol("force_leading_N", "nan")})
    out = tmp_path / "never"
    r = cli(REFERENCE, bad, "--out", out, "--set", SHORT[0], "--set", SHORT[1])
    assert r.returncode == 2 and "nan: line 12, column 'force_leading_N'" in r.stderr, r.stderr
    assert not out.exists()
    # An existing directory keeps what it held; no staging directory is left beside it.
    out.mkdir()
    (out / "keep.txt").write_text("x")
    r = cli(REFERENCE, clean.path, "--out", out, "--set", SHORT[0], "--set", SHORT[1], "--tolerance", "spread=1")
    assert r.returncode == 2 and "--tolerance spread=1 rejected" in r.stderr, r.stderr
    assert sorted(os.listdir(out)) == ["keep.txt"]
    assert sorted(os.listdir(tmp_path)) == sorted(["bad.csv", "bad.yaml", "never"])


def test_the_cli_names_a_refused_tolerance_as_the_option_gave_it(tmp_path, clean):
    # compare() names its tolerances' keys; the command line gave them as options.
    (tmp_path / "tol.yaml").write_text("std_force_N: abc\n")
    for args, words in ((["--tolerance", "std_force_N=abc"], "--tolerance std_force_N=abc rejected"),
                        (["--tolerance", "force_rms_difference_N=10%"],
                         "--tolerance force_rms_difference_N=10% rejected"),
                        (["--tolerances", str(tmp_path / "tol.yaml")], "tol.yaml: std_force_N: 'abc' rejected")):
        r = cli(REFERENCE, clean.path, "--out", tmp_path / "never", "--set", SHORT[0], "--set", SHORT[1], *args)
        assert r.returncode == 2 and words in r.stderr and "tolerances[" not in r.stderr, r.stderr
        assert not (tmp_path / "never").exists()


def _lines_and_metadata(record):
    """A record's CSV lines and its side YAML's metadata, as written."""
    with open(record.path) as f:
        lines = f.read().splitlines()
    with open(os.path.splitext(record.path)[0] + ".yaml") as f:
        return lines, yaml.safe_load(f)


# --------------------------------------------------------------------------------------------
# Other shapes of the same record
# --------------------------------------------------------------------------------------------
def test_a_header_a_railways_stations_and_a_time_based_record_read_alike(tmp_path, clean):
    lines, doc = _lines_and_metadata(clean)
    # The metadata as '#' lines atop the CSV instead of beside it.
    header = ["# " + ln for ln in yaml.safe_dump(doc).splitlines()]
    (tmp_path / "h.csv").write_text("\n".join(header + lines) + "\n")
    r = cm.read_record(str(tmp_path / "h.csv"))
    assert np.array_equal(r.station_m, clean.station_m)
    assert np.array_equal(r.force_N["leading"], clean.force_N["leading"])
    # Both at once is ambiguous.
    (tmp_path / "h.yaml").write_text(yaml.safe_dump(doc))
    refused(str(tmp_path / "h.csv"), "metadata", "metadata")
    # Stations counted from a kilometre post 12.345 km before the scene's station 0.
    head = lines[0].split(",")
    k = head.index("station_m")
    rows = [ln.split(",") for ln in lines[1:]]
    for row in rows:
        row[k] = "%.6f" % (float(row[k]) / 1000.0 + 12.345)
    head[k] = "station_km"
    (tmp_path / "km.csv").write_text("\n".join([",".join(head)] + [",".join(row) for row in rows]) + "\n")
    moved = dict(doc, station_origin_m=12345.0, supports={n: x + 12345.0 for n, x in doc["supports"].items()})
    (tmp_path / "km.yaml").write_text(yaml.safe_dump(moved))
    r = cm.read_record(str(tmp_path / "km.csv"))
    # km to 1e-6 is mm: the stations agree to half a millimetre.
    assert np.max(np.abs(r.station_m - clean.station_m)) <= 0.5e-3 + 1e-9
    assert r.support_station_m == pytest.approx(clean.support_station_m)
    # Without a station column: the stations are the speed integrated over the times from
    # start_station_m. The simulated train's speed is constant over each step (dt) and changes
    # between steps, so a speed sampled anywhere in a step misplaces that step's change by at most
    # dt: over the record at most (v_end - v_start) dt, about 10 mm here; the trapezoid rule on a
    # speed linear in station adds (dv/dt) h^2 / 12 per 5 ms row, 1e-7 m, 1e-4 m in all.
    (tmp_path / "t.csv").write_text("\n".join(",".join(c for j, c in enumerate(ln.split(",")) if j != lines[0]
                                                       .split(",").index("station_m")) for ln in lines) + "\n")
    (tmp_path / "t.yaml").write_text(yaml.safe_dump(dict(doc, start_station_m=float(clean.station_m[0]))))
    r = cm.read_record(str(tmp_path / "t.csv"))
    dt = cs.Simulation(REFERENCE, SHORT).dt
    assert np.max(np.abs(r.station_m - clean.station_m)) <= (RAMP[1][1] - RAMP[1][0]) / 3.6 * dt + 2e-4


def test_a_given_speed_profile_replaces_the_records(clean):
    # The record's run (230 to 270 km/h) compared against a pass at a constant 250 km/h: the
    # simulated train follows the given speed, and the record's stations still place the samples.
    c = cm.compare(REFERENCE, clean, overrides=SHORT, speed_profile=250.0)
    assert c.settings["speed_profile"] == "250 km/h throughout"
    assert np.allclose(c.series["simulated_speed_kmh"], 250.0)
    assert c.settings["mean_speed_kmh"] == pytest.approx(250.0)
    dev = {r["quantity"]: r["deviation"] for r in c.rows if r["of"] == "leading"}
    assert abs(dev["std_force_N"]) > 1e-3  # another run than the record's


def test_two_pantographs_share_the_section_and_the_steady_arms(tmp_path):
    # The leading pantograph of a two-pantograph train starts 200 m into the line: the default
    # section is the scene's analysis section where it runs, and a steady arm only the trailing
    # pantograph passes still has its uplift (the core takes it over all pantographs).
    scene = os.path.join(ROOT, "config", "reference_55m_two_pantographs.yaml")
    ov = ["numerics.element_length=0.5"]
    rec = cm.synthesise_record(scene, str(tmp_path / "two.csv"), overrides=ov)
    c = cm.compare(scene, rec, overrides=ov)
    assert c.settings["section_m"][0] == pytest.approx(rec.station_m[0])
    assert set(rec.force_N) == {"leading", "trailing"}
    uplift = [r for r in c.rows if r["quantity"] == "max_uplift_m"]
    assert uplift and all(r["record"] is not None and abs(r["deviation"]) < 1e-6 for r in uplift)
    # sampled at 200 Hz, the largest uplift is at most the core's every-step one
    core = max(p["max_uplift_at_support_m"] for p in c.run.stats["pantographs"])
    assert max(r["record"] for r in uplift) <= core + 0.5e-7


def test_the_statistics_filter_is_a_zero_phase_fourth_order_butterworth():
    # The core's filter (bound for the record's side) against scipy's own design of the same filter:
    # a 4th-order Butterworth by the bilinear transform pre-warped at fc, run forward and backward
    # from the steady state with odd reflection over ceil(3 fs / fc) samples. Two implementations of
    # one linear filter differ by rounding only: 1e-9 of the signal's 1 V scale is far above double
    # rounding over a few thousand multiply-adds and far below any design difference (a wrong Q or
    # an unwarped cutoff moves the output by 1e-3 or more).
    from scipy import signal
    fs, fc = 1000.0, 20.0
    t = np.arange(3000) / fs
    x = np.sin(2 * np.pi * 3.0 * t) + 0.5 * np.sin(2 * np.pi * 45.0 * t) + 0.2 * t
    sos = signal.butter(4, fc, btype="low", fs=fs, output="sos")
    ref = signal.sosfiltfilt(sos, x, padtype="odd", padlen=math.ceil(3.0 * fs / fc))
    assert np.max(np.abs(cm.lowpass(x, fs, fc) - ref)) < 1e-9
    # At or above Nyquist the series passes through.
    assert np.array_equal(cm.lowpass(x, fs, 600.0), x)


@pytest.mark.parametrize("x, fs, fc, named", [([1.0, 2.0, 3.0, 4.0], 0.0, 20.0, "sample rate fs = 0"),
                                              ([1.0, 2.0, 3.0, 4.0], 100.0, float("nan"), "cutoff fc = nan"),
                                              ([1.0, float("inf"), 3.0, 4.0], 100.0, 20.0, "sample 1 = inf")])
def test_the_filter_refuses_bad_input_by_name(x, fs, fc, named):
    with pytest.raises(ValueError, match=re.escape(named)):
        cm.lowpass(x, fs, fc)


def test_the_worked_example_writes_only_into_its_scratch_directory():
    # The page's commands run from the repository's root: every file they make (the synthesised
    # record, --out directories, the calibration file's record) lies in work/, which git ignores.
    with open(os.path.join(ROOT, "docs", "measured_records.md"), encoding="utf-8") as f:
        page = f.read()
    example = page[page.index("## A worked example"):page.index("## Tests")]
    written = re.findall(r"synthesise_record\([^,]+,\s*\"([^\"]+)\"", example)
    written += [d for d in re.findall(r"--out (\S+)", example) if d != "DIR"]  # DIR: the usage line
    read = re.findall(r"cm\.compare\([^,]+,\s*\"([^\"]+)\"", example)
    assert len(written) == 3 and len(read) == 1, (written, read)
    for p in written + read:
        assert p.startswith("work/"), p
    with open(os.path.join(ROOT, "docs", "measured_records_calibration.yaml"), encoding="utf-8") as f:
        cal = yaml.safe_load(f)
    record = os.path.normpath(os.path.join(ROOT, "docs", cal["record"]))
    assert record == os.path.join(ROOT, "work", "measured_run.csv")
    for p in written + [os.path.relpath(record, ROOT)]:
        r = subprocess.run(["git", "check-ignore", "-q", "--no-index", p], cwd=ROOT, timeout=60)
        assert r.returncode == 0, f"{p} is not ignored by git"


@pytest.mark.parametrize("kw, field", [
    ({"sample_rate_hz": 5e6}, "sample_rate_hz"),          # finer than the time column's 1 us
    ({"sample_rate_hz": 0.01}, "sample_rate_hz"),         # fewer than 3 rows over the pass
    ({"supports": "all"}, "supports"),
    ({"supports": 5}, "supports"),
    ({"head": "no"}, "head"),
    ({"path": "y.yaml"}, "path"),                         # the CSV where its side YAML belongs
    ({"path": "run.txt"}, "path"),
    ({"path": "missing/run.csv"}, "path"),
    ({"path": "."}, "path"),
])
def test_synthesise_record_refuses_bad_arguments_before_writing(tmp_path, kw, field):
    kw = dict(kw)
    path = str(tmp_path / kw.pop("path", "run.csv"))
    with pytest.raises(cs.SceneError) as e:
        cm.synthesise_record(REFERENCE, path, overrides=SHORT, **kw)
    assert e.value.field == field, str(e.value)
    assert f"{field} = " in str(e.value) and "allowed" in str(e.value)
    assert os.listdir(tmp_path) == []


def test_synthesise_record_leaves_nothing_when_a_file_cannot_be_placed(tmp_path, monkeypatch):
    # The CSV cannot be moved into place after its side YAML was: neither is left, nor a staged file.
    real = os.replace

    def replace(src, dst):
        if dst.endswith(".csv"):
            raise PermissionError(13, "Permission denied")
        return real(src, dst)
    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(cs.SceneError) as e:
        cm.synthesise_record(REFERENCE, str(tmp_path / "run.csv"), overrides=SHORT)
    assert e.value.field == "path" and "Permission denied" in str(e.value)
    assert os.listdir(tmp_path) == []


# --------------------------------------------------------------------------------------------
# Filters no longer than the record
# --------------------------------------------------------------------------------------------
def test_a_band_whose_period_exceeds_the_record_is_refused_by_its_name(tmp_path, clean):
    # The record spans rows / sample rate seconds; a low-pass whose period is longer has no whole
    # period of it to act on: refused, naming the least cutoff for this record.
    duration = len(clean.station_m) / clean.sample_rate_hz
    least = 1.0 / duration
    err = refused(write(tmp_path, clean, meta=lambda d: d.update(bandwidth_hz=0.5 * least)), "metadata",
                  "bandwidth_hz")
    assert f"at least {least:.4g} Hz" in str(err)
    with pytest.raises(cs.SceneError) as e:
        cm.compare(REFERENCE, clean, overrides=SHORT, cutoff_hz=0.5 * least)
    assert e.value.field == "cutoff_hz" and f"at least {least:.4g} Hz" in str(e.value)
    with pytest.raises(cs.SceneError) as e:  # the scene's own cutoff, as low
        cm.compare(REFERENCE, clean, overrides=SHORT + [f"output.filter_cutoff={0.5 * least!r}"])
    assert e.value.field == "cutoff_hz" and "output.filter_cutoff" in str(e.value)
    cm.compare(REFERENCE, clean, overrides=SHORT, cutoff_hz=1.01 * least)  # one period within: accepted
    out = tmp_path / "never"
    r = cli(REFERENCE, clean.path, "--out", out, "--set", SHORT[0], "--set", SHORT[1], "--cutoff", 0.5 * least)
    assert r.returncode == 2 and "--cutoff = " in r.stderr and f"at least {least:.4g} Hz" in r.stderr, r.stderr
    assert not out.exists()
    # The short pass lasts about 4 s (330 m at 300 km/h): 0.15 Hz is above the filter's least,
    # 0.1 Hz, and below one period within the record, about 0.25 Hz.
    with pytest.raises(cs.SceneError) as e:
        cm.synthesise_record(REFERENCE, str(tmp_path / "s.csv"), overrides=SHORT, bandwidth_hz=0.15)
    assert e.value.field == "bandwidth_hz" and "exceeds the record's duration" in str(e.value)
    with pytest.raises(cs.SceneError) as e:  # below the filter's least, whatever the record
        cm.synthesise_record(REFERENCE, str(tmp_path / "s.csv"), overrides=SHORT, bandwidth_hz=1e-3)
    assert e.value.field == "bandwidth_hz" and "[0.1, 10000]" in str(e.value)
    assert not (tmp_path / "s.csv").exists()


def test_a_bandwidth_beyond_the_measuring_pantographs_is_named_as_the_records(tmp_path, clean):
    # The record's bandwidth becomes the simulated measuring pantograph's output.sensor_bandwidth:
    # one beyond that field's range is the record's field, not a scene field the user never wrote.
    err = refused(write(tmp_path, clean, meta=lambda d: d.update(bandwidth_hz=1e6)), "metadata", "bandwidth_hz",
                  scene=True)
    assert "output.sensor_bandwidth" in err.allowed
    with pytest.raises(cs.SceneError) as e:
        cm.synthesise_record(REFERENCE, str(tmp_path / "s.csv"), overrides=SHORT, bandwidth_hz=1e6)
    assert e.value.field == "bandwidth_hz", str(e.value)
    assert not (tmp_path / "s.csv").exists()


# --------------------------------------------------------------------------------------------
# Files as spreadsheets and editors write them
# --------------------------------------------------------------------------------------------
def test_a_byte_order_mark_and_trailing_commas_read_as_the_plain_record(tmp_path, clean):
    lines, doc = _lines_and_metadata(clean)
    header = ["# " + ln for ln in yaml.safe_dump(doc).splitlines()]
    variants = {
        # a UTF-8 byte order mark before the '#' metadata lines
        "bom": ("\ufeff" + "\n".join(header + lines) + "\n", None),
        # ... and before a side YAML
        "bom_side": ("\n".join(lines) + "\n", "\ufeff" + yaml.safe_dump(doc)),
        # a trailing comma on every data row, on the header and the rows, on the header alone
        "rows": ("\n".join(lines[:1] + [ln + "," for ln in lines[1:]]) + "\n", yaml.safe_dump(doc)),
        "both": ("\n".join(ln + "," for ln in lines) + "\n", yaml.safe_dump(doc)),
        "head": ("\n".join([lines[0] + ","] + lines[1:]) + "\n", yaml.safe_dump(doc)),
    }
    for name, (csv_text, side) in variants.items():
        (tmp_path / f"{name}.csv").write_text(csv_text, encoding="utf-8")
        if side is not None:
            (tmp_path / f"{name}.yaml").write_text(side, encoding="utf-8")
        r = cm.read_record(str(tmp_path / f"{name}.csv"))
        assert list(r.columns.values()) == list(clean.columns.values()), name
        assert np.array_equal(r.station_m, clean.station_m), name
        assert np.array_equal(r.force_N["leading"], clean.force_N["leading"]), name
        assert r.support_station_m == clean.support_station_m, name
    # A row with a field more than the header (not an empty trailing one) is refused by its line.
    refused(write(tmp_path, clean, {20: lambda r, h: r + ["7"]}), "format", "row", 22)


def test_metadata_of_the_wrong_shape_is_refused_saying_what_was_read(tmp_path, clean):
    refused(write(tmp_path, clean, meta=lambda d: d.update(station_of=["leading"])), "metadata", "station_of")
    refused(write(tmp_path, clean, meta=lambda d: d.update(station_of={"a": 1})), "metadata", "station_of")
    refused(write(tmp_path, clean, meta=lambda d: d.update(pantographs=[{"a": 1}])), "metadata", "pantographs")
    refused(write(tmp_path, clean, meta=lambda d: d.update(pantographs=[["leading"]])), "metadata", "pantographs")
    # A quoted number is text: shown quoted, as read, not as the number it looks like.
    err = refused(write(tmp_path, clean, meta=lambda d: d.update(sample_rate_hz="200")), "metadata",
                  "sample_rate_hz")
    assert "'sample_rate_hz' = '200'" in str(err) and "not a number" in str(err)


def test_a_section_of_fewer_than_three_rows_is_refused_with_the_rows_it_holds(tmp_path, clean):
    x = clean.station_m
    k = int(np.searchsorted(x, 160.0))  # inside the analysis section, within one span (110-165 m)
    two = [float(x[k]), float(x[k + 1])]  # bounds included: two rows
    err = refused(write(tmp_path, clean, meta=lambda d: d.update(section_m=two), name="two.csv"), "short_section",
                  "section_m", scene=True)
    assert "holds 2 of the record's rows" in str(err) and "at least 3 rows" in str(err)
    # Three rows are enough for every statistic and the spectrum, without a warning.
    three = write(tmp_path, clean, meta=lambda d: d.update(section_m=[float(x[k]), float(x[k + 2])]), name="3.csv")
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        c = cm.compare(REFERENCE, three, overrides=SHORT)
    assert c.settings["rows_in_section"] == 3


def test_the_span_passing_frequency_is_the_lines_span_at_the_mean_speed(tmp_path, clean):
    # A section inside one span holds no two supports: the span is still the line's (55 m here),
    # not the section's length. Both sides of the check are the same division: 1e-12 relative.
    with open(REFERENCE) as f:
        span = yaml.safe_load(f)["line"]["span_length"]
    for section in ([150.0, 160.0], [100.0, 250.0]):
        rec = write(tmp_path, clean, meta=lambda d: d.update(section_m=section), name="sec.csv")
        c = cm.compare(REFERENCE, rec, overrides=SHORT)
        v = c.settings["mean_speed_kmh"] / 3.6
        assert c.settings["span_passing_hz"] == pytest.approx(v / span, rel=1e-12), section


@pytest.mark.parametrize("tolerances, words", [
    # a difference of the two sides has no record's value to take a percentage of
    ({"force_rms_difference_N": "10%"}, "is itself a difference"),
    ({"leading.spectrum_rms_difference_dB": "5 %"}, "is itself a difference"),
    # an owner without such a row, a quantity no owner has
    ({"A2.mean_force_N": 1}, "A2 has no mean_force_N"),
    ({"leading.max_uplift_m": 0.01}, "leading has no max_uplift_m"),
    ({"trailing.mean_force_N": 1}, "'trailing.mean_force_N'"),
])
def test_a_tolerance_the_comparison_cannot_apply_is_refused(clean, tolerances, words):
    with pytest.raises(cs.SceneError) as e:
        cm.compare(REFERENCE, clean, overrides=SHORT, tolerances=tolerances)
    assert words in str(e.value) and "allowed" in str(e.value), str(e.value)


def test_a_tolerance_of_the_head_needs_a_head_column(tmp_path, clean):
    with open(clean.path) as f:
        rows = [ln.split(",") for ln in f.read().splitlines()]
    k = rows[0].index("head_leading_mm")
    (tmp_path / "bare.csv").write_text("\n".join(",".join(r[:k] + r[k + 1:]) for r in rows) + "\n")
    with open(os.path.splitext(clean.path)[0] + ".yaml") as f:
        (tmp_path / "bare.yaml").write_text(f.read())
    with pytest.raises(cs.SceneError) as e:
        cm.compare(REFERENCE, str(tmp_path / "bare.csv"), overrides=SHORT, tolerances={"head_std_m": 1e-3})
    assert "the record has no head_std_m" in str(e.value) and "head column" in str(e.value)


@pytest.mark.parametrize("call, named", [
    (lambda: cm.lowpass([1.0, 2.0, 3.0, 4.0], 100.0, "a"), "cutoff fc = 'a'"),
    (lambda: cm.lowpass([1.0, 2.0, 3.0, 4.0], None, 20.0), "sample rate fs = None"),
    (lambda: cm.lowpass([[1.0, 2.0], [3.0, 4.0]], 100.0, 20.0), "x = [[1.0, 2.0], [3.0, 4.0]]"),
    (lambda: cm.lowpass(["a", "b"], 100.0, 20.0), "x = ['a', 'b']"),
    (lambda: cm.section_statistics([1.0, 2.0, 3.0], [0, 1, 1]), "inside = [0, 1, 1]"),  # not an index
    (lambda: cm.section_statistics([1.0, 2.0, 3.0], np.array([True, True])), "inside = "),
    (lambda: cm.section_statistics([1.0, float("nan"), 3.0], np.ones(3, bool)), "force[1] = nan"),
    (lambda: cm.section_statistics([1.0, 2.0, 3.0], np.ones(3, bool), [1.0, 2.0]), "loss_force = [1.0, 2.0]"),
    (lambda: cm.noise_after_filters(-3.0, 200.0, [20.0]), "noise_std = -3.0"),
    (lambda: cm.noise_after_filters(3.0, float("nan"), [20.0]), "fs = nan"),
    (lambda: cm.noise_after_filters(3.0, 200.0, [0.0]), "cutoffs[0] = 0.0"),
    (lambda: cm.noise_after_filters(3.0, 200.0, 20.0), "cutoffs = 20.0"),
    (lambda: cm.noise_after_filters(3.0, 200.0, [20.0], n=0), "n = 0"),
    (lambda: cm.simulate_run(REFERENCE, None, SHORT, 280.0, max_steps=float("nan")), "max_steps = nan"),
    (lambda: cm.simulate_run(REFERENCE, None, SHORT, 280.0, max_steps="many"), "max_steps = 'many'"),
    (lambda: cm.simulate_run(REFERENCE, 5, SHORT), "record = 5"),
])
def test_the_functions_refuse_bad_arguments_by_name(call, named):
    with pytest.raises(ValueError) as e:
        call()
    assert named in str(e.value) and "allowed" in str(e.value), str(e.value)


def test_a_record_error_crosses_processes_whole():
    # A calibration's Dask worker sends its errors back pickled: the kind, field and line survive.
    import pickle
    err = cm.RecordError("nan", "run.csv", "force_leading_N", "'x'", "a finite number", "not a number", row=12)
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is cm.RecordError and str(back) == str(err)
    assert (back.kind, back.field, back.row, back.path) == ("nan", "force_leading_N", 12, "run.csv")


# --------------------------------------------------------------------------------------------
# Arguments and files each refused by name, with nothing left behind
# --------------------------------------------------------------------------------------------
def test_the_filters_and_spectra_refuse_what_is_no_real_series_or_rate():
    # An imaginary part is no force: numpy would drop it with a warning.
    with pytest.raises(cs.SceneError) as e:
        cm.lowpass(np.full(50, 100 + 5j), 200.0, 20.0)
    assert e.value.field == "x"
    for fs in (0.0, float("nan"), -5.0):
        with pytest.raises(cs.SceneError) as e:
            cm.welch_spectrum(np.ones(100), fs, 1.0)
        assert e.value.field == "fs"
    with pytest.raises(cs.SceneError) as e:
        cm.spectral_peaks(np.arange(10.0), np.ones(10), 50.0, 1.5)
    assert e.value.field == "count"
    with pytest.raises(cs.SceneError) as e:
        cm.spectral_peaks(np.arange(10.0), np.ones(9), 50.0)
    assert e.value.field == "p"


def test_a_speed_profile_file_and_a_record_header_are_checked_as_their_code_forms(tmp_path, clean):
    profile = tmp_path / "profile.csv"
    profile.write_text("station_m,speed_kmh\n0,nan\n100,250\n")
    with pytest.raises(cs.SceneError) as e:
        cm.read_speed_profile(str(profile))
    assert e.value.field == "speed_profile" and "540 km/h" in str(e.value)
    # A force column that names no pantograph (force__N) is no column of a record.
    bad = write(tmp_path, clean, header=lambda h: [("force__N" if c.startswith("force_") else c) for c in h])
    refused(bad, "unknown_column", "force__N")
    # A field beyond the csv module's limit is a format fault of the file, by name.
    refused(write(tmp_path, clean, header=lambda h: h + ["9" * 200000], name="long.csv"), "format", "file")


def test_a_comparison_is_written_whole_or_refused_with_nothing_moved(tmp_path, clean):
    c = cm.compare(REFERENCE, clean, overrides=SHORT)
    for directory, flags, field in (("", {}, "directory"), (tmp_path / "a", {"report": "no"}, "report"),
                                    (tmp_path / "a", {"pass_files": 1}, "pass_files")):
        with pytest.raises(cs.SceneError) as e:
            c.write(directory, **flags)
        assert e.value.field == field
    assert not (tmp_path / "a").exists()
    # Into an existing directory whose comparison.json is a directory: nothing moves in.
    target = tmp_path / "cmp"
    (target / "comparison.json").mkdir(parents=True)
    with pytest.raises(cs.SceneError) as e:
        c.write(target, pass_files=False)
    assert e.value.field == "directory" and "comparison.json is a directory" in str(e.value)
    assert sorted(os.listdir(target)) == ["comparison.json"]
    assert [n for n in os.listdir(tmp_path) if n.startswith(".cmp.")] == []


def test_a_synthesised_record_the_records_checks_refuse_names_the_noise(tmp_path):
    # 5 kN of noise on a force of about 100 N carries the record beyond a plausible one's forces.
    path = tmp_path / "n.csv"
    with pytest.raises(cs.SceneError) as e:
        cm.synthesise_record(REFERENCE, str(path), overrides=SHORT, speed_profile=250.0, noise_std_N=5000.0)
    assert e.value.field == "noise_std_N" and "n.csv." not in str(e.value)
    assert os.listdir(tmp_path) == []


def test_a_profile_faster_than_the_line_allows_is_refused_by_the_profile(clean):
    # The reference contact wire's wave speed is about 460 km/h: 500 km/h is within the argument's
    # 540 but beyond the scene, and named by the profile, not the scene's train.speed_kmh.
    with pytest.raises(cs.SceneError) as e:
        cm.compare(REFERENCE, clean, overrides=SHORT, speed_profile=500.0)
    assert e.value.field == "speed_profile" and "wave speed" in str(e.value)
    with pytest.raises(cs.SceneError) as e:
        cm.compare(REFERENCE, clean, overrides=SHORT, speed_profile=([0.0, 200.0], [250.0, 500.0]))
    assert e.value.field == "speed_profile"
