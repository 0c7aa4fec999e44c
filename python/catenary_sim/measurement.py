"""Measured records beside the simulation: read and check a line-test record, simulate the same
run, and compare the two with the same filter, analysis section and statistics (EN 50318's third
way of making a simulation credible: comparison with line-test measurements).

    from catenary_sim import measurement as cm
    record = cm.read_record("run.csv")                        # run.yaml beside it, or a '#' header
    comparison = cm.compare("config/reference_55m.yaml", record, tolerances={"std_force_N": "10%"})
    comparison.write("out_cmp/")                              # CSVs, comparison.json, report.html
    cm.synthesise_record("config/reference_55m.yaml", "synthetic.csv", noise_std_N=5.0)

The record format, the definitions and a worked example: docs/measured_records.md. The
simulated side is the core's (catenary_sim.Simulation, driven by the record's speed profile
through set_speed); the measuring pantograph's view of it is the core's (force_processed.csv,
output.sensor_bandwidth set to the record's bandwidth). Here only filtering, sampling and the
statistics that are applied identically to both sides.
"""
import csv
import json
import math
import os
import re
import shutil
import tempfile
import textwrap
from collections.abc import Iterable

import numpy as np
import pandas as pd
import yaml
from scipy import signal

from . import SceneError, Simulation, _core, _override_list, _path, _real, _integer, _refuse, _shown
from . import _files

__all__ = ["RecordError", "Record", "read_record", "simulate_run", "compare", "Comparison",
           "synthesise_record", "lowpass", "section_statistics", "STATISTICS"]

# Column grammar: quantity[_name]_unit; the factor turns the unit into SI.
UNITS = {
    "station": {"m": 1.0, "km": 1000.0},
    "time": {"s": 1.0, "ms": 1e-3},
    "speed": {"kmh": 1.0 / 3.6, "mps": 1.0},
    "force": {"N": 1.0, "kN": 1000.0},
    "uplift": {"m": 1.0, "mm": 1e-3},
    "head": {"m": 1.0, "mm": 1e-3},
}
NAMED = ("force", "uplift", "head")  # quantities with a pantograph's or a support's name
# Values no measuring run produces in these SI units: a value beyond is a wrong unit or damage.
# Forces of a pantograph under a contact wire are tens to hundreds of newtons (EN 50367's target
# mean forces are 70-250 N); a record whose mean is below 10 N is not a contact force in N.
PLAUSIBLE = {"station": (-1e7, 1e7), "time": (-1e7, 1e7), "speed": (0.0, 150.0), "force": (-1000.0, 5000.0),
             "uplift": (-1.0, 1.0), "head": (-2.0, 2.0)}
PLAUSIBLE_TEXT = {"station": "+-10,000 km", "time": "+-10^7 s", "speed": "0 to 540 km/h",
                  "force": "-1 to 5 kN", "uplift": "+-1 m", "head": "+-2 m"}
MIN_MEAN_FORCE_N = 10.0
METADATA = {"sample_rate_hz", "bandwidth_hz", "pantographs", "station_of", "station_origin_m", "start_station_m",
            "section_m", "supports", "max_gap_samples", "name", "description", "line", "date", "vehicle",
            "direction"}
# Two speeds (the speed column against the stations' advance) agreeing within this share are the
# same unit: a speed in m/s labelled km/h is off by 3.6, a sample rate off by a factor of 2 by 100 %.
UNIT_AGREEMENT = 0.10
# The record's statistics, in the order of the table; "loss" share of samples with force <= 0.
STATISTICS = ("mean_force_N", "std_force_N", "stat_max_force_N", "stat_min_force_N", "max_force_N", "min_force_N",
              "contact_loss_percent")
DIFFERENCES = ("force_rms_difference_N", "force_max_abs_difference_N", "spectrum_rms_difference_dB")
HEAD = ("head_std_m", "head_range_m")
# The fewest rows an analysis section holds: a mean, a spread and a spectrum need three samples.
MIN_SECTION_ROWS = 3
UPLIFT = ("max_uplift_m",)
TOLERANCE_NAMES = STATISTICS + DIFFERENCES + HEAD + UPLIFT


class RecordError(SceneError):
    """A record that cannot be used. kind names the class of fault (one of KINDS), field the column
    or metadata key, row the file's line number (1 = the first line; None: the whole column or
    file), value the value as written, allowed what would be accepted."""

    KINDS = ("format", "metadata", "missing_column", "unknown_column", "unknown_unit", "wrong_unit", "nan",
             "non_monotonic", "gap", "unknown_pantograph", "unknown_support", "section_outside_line",
             "speed_profile", "short_section")

    def __init__(self, kind, path, field, value, allowed, why, row=None):
        where = f"line {row}, " if row is not None else ""
        if kind == "format":
            what = f"{field} {value}"
        else:
            what = f"{'field' if kind in ('metadata', 'section_outside_line', 'short_section') else 'column'} " \
               f"'{field}' = {value}"
        message = f"record {path}: {kind}: {where}{what}: {why}; allowed {allowed}"
        super().__init__(message, field=field, value=value, allowed=allowed)
        self.kind, self.row, self.path = kind, row, path
        self._args = (kind, path, field, value, allowed, why, row)

    def __reduce__(self):
        # Rebuilt from its own arguments when it crosses processes (a calibration's Dask worker).
        return (self.__class__, self._args)


class Record:
    """A checked record in SI units and the scene's stations (station_m of the reference pantograph,
    station_of). force_N, head_m: per pantograph; uplift_m: per support name, whose model station is
    support_station_m[name]. time_s and speed_mps are None when the record has no such column."""

    def __init__(self, **kw):
        self.__dict__.update(kw)

    def __repr__(self):
        return (f"Record({self.path!r}, {len(self.station_m)} rows, {self.sample_rate_hz:g} Hz, "
                f"bandwidth {self.bandwidth_hz:g} Hz, pantographs {list(self.force_N)})")


# --------------------------------------------------------------------------------------------
# Reading and checking a record
# --------------------------------------------------------------------------------------------
def _read_metadata(path, meta, comment_lines):
    side = meta
    if side is None:
        stem = os.path.splitext(path)[0]
        for ext in (".yaml", ".yml"):
            if os.path.isfile(stem + ext):
                side = stem + ext
    # '# key: value' lines: the '#' and the indent they share removed, nested YAML kept.
    header = textwrap.dedent("\n".join(line[1:] for line in comment_lines))
    header = header if header.strip() else ""
    if side is not None and header:
        raise RecordError("metadata", path, "metadata", side, "the metadata in one place only",
                          "given both in the CSV's '#' header and in a side YAML")
    try:
        if side is not None:
            with open(side, encoding="utf-8-sig") as f:  # a byte order mark is no part of the YAML
                doc = yaml.safe_load(f)
        else:
            doc = yaml.safe_load(header) if header else None
    except (OSError, yaml.YAMLError, UnicodeDecodeError) as e:
        raise RecordError("metadata", path, "metadata", side or "# header", "a YAML map of the fields below",
                          f"cannot be read ({str(e).splitlines()[0]})") from None
    if not isinstance(doc, dict):
        raise RecordError("metadata", path, "metadata", side or "# header",
                          "a YAML map with sample_rate_hz and bandwidth_hz (a side RECORD.yaml or '# key: value' "
                          "lines atop the CSV)", "missing or not a map")
    for key in doc:
        if key not in METADATA:
            raise RecordError("metadata", path, str(key), _shown(doc[key]), ", ".join(sorted(METADATA)),
                              "not a metadata field")
    return doc


def _meta_real(doc, path, key, low, high, allowed, default=None, required=True):
    if key not in doc:
        if required:
            raise RecordError("metadata", path, key, "absent", allowed, "required")
        return default
    v = doc[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise RecordError("metadata", path, key, _shown(v), allowed + " (a number, not quoted)",
                          f"not a number (read as {type(v).__name__})")
    if not math.isfinite(v) or not low <= v <= high:
        raise RecordError("metadata", path, key, _shown(v), allowed, "out of range")
    return float(v)


def _parse_columns(path, names):
    """{column: (quantity, name, unit)}; refuses an unknown column or unit."""
    out = {}
    for col in names:
        parts = str(col).split("_")
        quantity, unit = parts[0], parts[-1]
        allowed_cols = ("station_m|km, time_s|ms, speed_kmh|mps, force_PANTOGRAPH_N|kN, uplift_SUPPORT_mm|m, "
                        "head_PANTOGRAPH_mm|m")
        # (a named quantity's name not empty: force__N names no pantograph)
        if (quantity not in UNITS or len(parts) < 2 or (quantity in NAMED) != (len(parts) >= 3)
                or (quantity in NAMED and not "_".join(parts[1:-1]))):
            raise RecordError("unknown_column", path, col, "(header)", allowed_cols, "not a column of a record")
        if unit not in UNITS[quantity]:
            raise RecordError("unknown_unit", path, col, unit, f"{quantity} in " + ", ".join(UNITS[quantity]),
                              "not a unit of " + quantity)
        out[col] = (quantity, "_".join(parts[1:-1]) or None, unit)
    return out


def _check_fields(path, lines, skip):
    """Refuses a row with more fields than the header (pandas would drop them); returns whether
    the header ends in an empty field (a trailing comma) with every row as long or one shorter."""
    try:
        rows = list(csv.reader(lines[skip:]))
    except csv.Error as e:
        raise RecordError("format", path, "file", path, "a CSV with a header line and one row per sample",
                          str(e)) from None
    if not rows or not rows[0]:
        return False
    head = rows[0]
    trailing = len(head) > 1 and head[-1].strip() == ""
    names = len(head) - trailing
    for k, row in enumerate(rows[1:]):
        extra = row[names:]
        if extra and not (len(extra) == 1 and extra[0].strip() == ""):
            raise RecordError("format", path, "row", f"of {len(row)} fields",
                              f"at most the header's {names} fields (and a trailing comma)",
                              "more fields than the header", row=skip + k + 2)
    return trailing


def read_record(path, meta=None):
    """Reads and checks a record (CSV; metadata from `meta`, a side YAML of the same stem, or '#'
    lines atop the CSV). Returns a Record in SI units; raises RecordError naming the class of fault,
    the line, the column, the value and what is allowed. The scene's own checks (pantographs,
    supports, the section within the line) are made by compare() and simulate_run()."""
    path = _path("record", path, "a CSV file path (str or os.PathLike)")
    if meta is not None:
        meta = _path("meta", meta, "a YAML file path (str or os.PathLike)")
    try:
        with open(path, encoding="utf-8-sig", newline="") as f:  # a byte order mark is no part of the text
            lines = f.read().splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise RecordError("format", path, "file", path, "a UTF-8 CSV file", f"cannot be read ({e})") from None
    comments = []
    while len(comments) < len(lines) and lines[len(comments)].startswith("#"):
        comments.append(lines[len(comments)])
    doc = _read_metadata(path, meta, comments)
    header_line = len(comments) + 1
    trailing = _check_fields(path, lines, len(comments))
    try:
        # index_col=False: a trailing comma on every row is an empty last field, not a shift of the
        # columns by one (the first taken as the index); _check_fields refuses longer rows.
        frame = pd.read_csv(path, skiprows=len(comments), dtype=str, keep_default_na=False, skip_blank_lines=False,
                            comment=None, encoding="utf-8-sig", index_col=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, ValueError, csv.Error) as e:
        raise RecordError("format", path, "file", path, "a CSV with a header line and one row per sample",
                          str(e).strip().splitlines()[0]) from None
    if trailing:
        frame = frame.iloc[:, :-1]
    if len(frame) < 3:
        raise RecordError("format", path, "rows", len(frame), "at least 3 rows under the header",
                          "too few samples")
    dup = [c for c in frame.columns if re.search(r"\.\d+$", str(c)) and str(c).rsplit(".", 1)[0] in frame.columns]
    if dup:
        raise RecordError("format", path, dup[0].rsplit(".", 1)[0], "(header)", "each column once", "given twice")
    cols = _parse_columns(path, frame.columns)
    sample_rate = _meta_real(doc, path, "sample_rate_hz", 1e-3, 1e7, "a sample rate in Hz, > 0")
    bandwidth = _meta_real(doc, path, "bandwidth_hz", 1e-3, 1e7, "the measuring chain's bandwidth in Hz, > 0")
    max_gap = _meta_real(doc, path, "max_gap_samples", 1.0, 1e6, "a number of sample intervals >= 1", 1.5, False)
    origin = _meta_real(doc, path, "station_origin_m", -1e7, 1e7, "the record's station of the scene's station 0 "
                        "(m)", 0.0, False)

    def values(col):
        quantity, _, unit = cols[col]
        text = frame[col]
        num = pd.to_numeric(text.str.strip(), errors="coerce").to_numpy(dtype=float)
        bad = ~np.isfinite(num)
        if bad.any():
            k = int(np.argmax(bad))
            raw = text.iloc[k]
            raise RecordError("nan", path, col, repr(raw), "a finite number in every row (a gap in the record is "
                              "refused: cut the record there)", "empty, not a number, NaN or infinite",
                              row=header_line + 1 + k)
        si = num * UNITS[quantity][unit]
        lo, hi = PLAUSIBLE[quantity]
        out = (si < lo) | (si > hi)
        if out.any():
            k = int(np.argmax(out))
            raise RecordError("wrong_unit", path, col, text.iloc[k], f"{PLAUSIBLE_TEXT[quantity]} once converted "
                              f"from {unit}", "beyond what a measuring run records: a wrong unit?",
                              row=header_line + 1 + k)
        return si

    by = {}
    for col, (quantity, name, _unit) in cols.items():
        key = (quantity, name)
        if key in by:
            raise RecordError("format", path, col, "(header)", "one column per quantity",
                              f"{quantity} {name or ''} given twice in different units")
        by[key] = col
    data = {key: values(col) for key, col in by.items()}
    forces = {name: v for (q, name), v in data.items() if q == "force"}
    if not forces:
        raise RecordError("missing_column", path, "force_PANTOGRAPH_N", "absent", "at least one force column",
                          "a record holds the contact force")
    for name, v in forces.items():
        if not np.mean(v) >= MIN_MEAN_FORCE_N:
            raise RecordError("wrong_unit", path, by[("force", name)], f"mean {np.mean(v):.4g} N",
                              f"a mean of at least {MIN_MEAN_FORCE_N:g} N", "too small for a contact force: "
                              "kN written as N?")
    listed = doc.get("pantographs", list(forces))
    if (not isinstance(listed, list) or not all(isinstance(n, str) for n in listed)
            or sorted(listed) != sorted(forces)):
        raise RecordError("metadata", path, "pantographs", _shown(listed), "the names of the force columns: "
                          + ", ".join(forces), "does not match the force columns")
    station_of = doc.get("station_of", listed[0])
    if not isinstance(station_of, str) or station_of not in forces:
        raise RecordError("metadata", path, "station_of", _shown(station_of), "one of " + ", ".join(forces),
                          "not a measured pantograph")
    for (q, name) in data:
        if q == "head" and name not in forces:
            raise RecordError("unknown_column", path, by[(q, name)], "(header)", "head_P_mm for a pantograph P "
                              "with a force column: " + ", ".join(forces), "no such measured pantograph")
    time = data.get(("time", None))
    speed = data.get(("speed", None))
    station = data.get(("station", None))
    row0 = header_line + 1
    for key in (("time", None), ("station", None)):
        if key in data:
            d = np.diff(data[key])
            if (d <= 0).any():
                k = int(np.argmax(d <= 0))
                raise RecordError("non_monotonic", path, by[key], frame[by[key]].iloc[k + 1],
                                  f"values increasing from row to row (after {frame[by[key]].iloc[k]})",
                                  "not after the row before" + (": a run against the stations is given with "
                                                                 "stations counted the train's way" if key[0] ==
                                                                 "station" else ""), row=row0 + k + 1)
    if speed is not None and (speed <= 0).any():
        k = int(np.argmax(speed <= 0))
        raise RecordError("speed_profile", path, by[("speed", None)], frame[by[("speed", None)]].iloc[k],
                          "speeds > 0 (cut the record before and after a stop)", "a stop", row=row0 + k)
    if station is None:
        if time is None:
            raise RecordError("missing_column", path, "station_m", "absent", "a station_m (or _km) column, or time_s "
                              "with speed and start_station_m", "a record needs its stations")
        start = _meta_real(doc, path, "start_station_m", -1e7, 1e7, "the record's station at its first row (m), "
                           "for a record without a station column")
        if speed is None:
            raise RecordError("missing_column", path, "speed_kmh", "absent", "a speed column with a time-based "
                              "record that has no stations", "the stations cannot be found")
        station = start + np.concatenate(([0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(time))))
    # The time between rows: from the time column, else from the stations and the speed, else
    # from the stations' median step (a record without time or speed).
    if time is not None:
        dt = np.diff(time)
    elif speed is not None:
        dt = np.diff(station) / (0.5 * (speed[1:] + speed[:-1]))
    else:
        dt = np.diff(station) / np.median(np.diff(station)) / sample_rate
    # Units that contradict each other: the declared sample rate against the rows' times, the
    # speed against the stations' advance.
    ratio = np.median(dt) * sample_rate
    if abs(ratio - 1.0) > UNIT_AGREEMENT:
        src = by.get(("time", None)) or by.get(("speed", None)) or "station"
        raise RecordError("wrong_unit", path, src if time is not None or speed is not None else "sample_rate_hz",
                          f"median row interval {np.median(dt):.4g} s",
                          f"1 / sample_rate_hz = {1.0 / sample_rate:.4g} s within {100 * UNIT_AGREEMENT:g} %",
                          "the rows do not follow the declared sample rate: a wrong unit or sample rate?")
    if time is not None and speed is not None and ("station", None) in data:
        advance = np.median(np.diff(station) / np.diff(time))
        if abs(advance / np.median(speed) - 1.0) > UNIT_AGREEMENT:
            raise RecordError("wrong_unit", path, by[("speed", None)], f"median {np.median(speed):.4g} m/s",
                              f"the stations' advance, {advance:.4g} m/s, within {100 * UNIT_AGREEMENT:g} %",
                              "the speed contradicts the stations and times: a wrong unit?")
    gap = dt * sample_rate > max_gap
    if gap.any():
        k = int(np.argmax(gap))
        col = by.get(("time", None)) or by.get(("station", None))
        raise RecordError("gap", path, col, frame[col].iloc[k + 1] if col else f"{dt[k]:.4g} s",
                          f"at most {max_gap:g} sample intervals between rows (metadata max_gap_samples)",
                          f"{dt[k] * sample_rate:.3g} sample intervals after the row before", row=row0 + k + 1)
    least = least_band_hz(len(frame), sample_rate)
    if bandwidth < least:
        raise RecordError("metadata", path, "bandwidth_hz", _shown(doc["bandwidth_hz"]),
                          f"at least {least:.4g} Hz for this record ({len(frame)} rows at {sample_rate:g} Hz, "
                          f"{1.0 / least:.4g} s)", "its period exceeds the record's duration")
    supports = doc.get("supports", {}) or {}
    if not isinstance(supports, dict):
        raise RecordError("metadata", path, "supports", _shown(supports), "a map SUPPORT: station (m)", "not a map")
    for name, x in supports.items():  # YAML reads an unquoted 2 as a number: the column's name is text
        if not isinstance(name, str):
            raise RecordError("metadata", path, f"supports.{name}", _shown(x),
                              f"a support's name as text, as in its uplift column (write '{name}': in quotes)",
                              "YAML read the key as " + ("a number" if isinstance(name, (int, float)) else
                                                         type(name).__name__) + ", not as text")
    uplift = {name: v for (q, name), v in data.items() if q == "uplift"}
    for name in uplift:
        if name not in supports:
            raise RecordError("unknown_support", path, by[("uplift", name)], "(header)",
                              "a support declared in the metadata's supports (given: "
                              f"{', '.join(map(str, supports)) or 'none'})",
                              "the record does not say where this support stands")
    support_station = {}
    for name, x in supports.items():
        if name not in uplift:
            raise RecordError("metadata", path, f"supports.{name}", _shown(x), "supports with an uplift_NAME column",
                              "no uplift column for it")
        support_station[name] = _meta_real(supports, path, name, -1e7, 1e7, "a station (m)") - origin
    section = doc.get("section_m")
    if section is not None:
        if (not isinstance(section, list) or len(section) != 2 or
                not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in section)
                or not section[0] < section[1]):
            raise RecordError("metadata", path, "section_m", _shown(section), "[start, end] in m, start < end",
                              "not a section")
        section = (float(section[0]) - origin, float(section[1]) - origin)
    return Record(path=path, sample_rate_hz=sample_rate, bandwidth_hz=bandwidth, station_origin_m=origin,
                  station_m=station - origin, time_s=time, speed_mps=speed, force_N=forces, station_of=station_of,
                  head_m={name: v for (q, name), v in data.items() if q == "head"}, uplift_m=uplift,
                  support_station_m=support_station, section_m=section, metadata=doc, columns=by,
                  first_row=row0)


# --------------------------------------------------------------------------------------------
# The same filter and statistics for both sides
# --------------------------------------------------------------------------------------------
def lowpass(x, fs, fc):
    """The core's zero-phase low-pass (output/zero_phase_filter.cpp), the filter of stats.json: a
    4th-order Butterworth run forward and backward with odd reflection at both ends; a cutoff at or
    above Nyquist passes the series through. x: a 1-D sequence of numbers; fs, fc: numbers, fc at
    least 0.1 Hz, the scene's least output.filter_cutoff (the core names a sample that is not
    finite)."""
    x = _series("x", x, finite=False)
    fs = _real("sample rate fs", fs, "a finite rate > 0 Hz", 1e-300)
    fc = _real("cutoff fc", fc, "a finite frequency of at least 0.1 Hz", 0.1)
    return np.asarray(_core._lowpass_zero_phase(x, fs, fc))


def _series(name, x, length=None, finite=True):
    """x as a 1-D float array, refused by name unless it is one of (finite) real numbers (of `length`)."""
    try:
        a = None if np.iscomplexobj(np.asarray(x)) else np.asarray(x, dtype=float)  # (an imaginary part is no force)
    except (TypeError, ValueError):
        a = None
    if a is None or a.ndim != 1 or (length is not None and len(a) != length):
        _refuse(name, x, "a 1-D sequence of numbers" + (f" of length {length}" if length is not None else ""))
    bad = ~np.isfinite(a) if finite else np.zeros(a.shape, dtype=bool)
    if bad.any():
        k = int(np.argmax(bad))
        _refuse(f"{name}[{k}]", a[k], "finite numbers")
    return a


def section_statistics(force, inside, loss_force=None):
    """The statistics of stats.json on one force series over the samples `inside` (a boolean mask):
    mean, population std, mean +- 3 std, the actual max and min, and the share of samples with
    loss_force (default: force) <= 0, in percent."""
    force = _series("force", force)
    mask = np.asarray(inside)
    if mask.dtype != bool or mask.shape != force.shape:
        _refuse("inside", inside, f"a boolean mask of the force's length ({len(force)})")
    loss = _series("loss_force", loss_force, len(force)) if loss_force is not None else force
    f = force[mask]
    lf = loss[mask]
    if f.size == 0:
        return {k: None for k in STATISTICS}
    mean, std = float(np.mean(f)), float(np.std(f))
    return {"mean_force_N": mean, "std_force_N": std, "stat_max_force_N": mean + 3 * std,
            "stat_min_force_N": mean - 3 * std, "max_force_N": float(np.max(f)), "min_force_N": float(np.min(f)),
            "contact_loss_percent": 100.0 * float(np.count_nonzero(lf <= 0.0)) / f.size}


def welch_spectrum(force, fs, segment_s):
    """Welch's PSD as the core takes it (line_measures.cpp): periodic Hann, half-overlapping
    segments of segment_s (the whole series when shorter), mean removed per segment, one-sided
    density, zero-padded to a power of two."""
    x = _series("force", force)
    fs = _real("fs", fs, "a sample rate in Hz > 0", 1e-300)
    segment_s = _real("segment_s", segment_s, "a segment length in s > 0", 1e-300)
    if len(x) < 2:
        _refuse("force", force, "at least 2 samples")
    nper = int(min(len(x), max(8, round(segment_s * fs))))
    nfft = 1 << (nper - 1).bit_length()
    return signal.welch(x, fs=fs, window="hann", nperseg=nper, noverlap=nper // 2, nfft=nfft,
                        detrend="constant", scaling="density")


def spectral_peaks(f, p, fmax, count=5):
    """The strongest local maxima between 2 resolutions and fmax at least 4 resolutions apart,
    with the amplitude of the equivalent sine, sqrt(2 x the power within +-3 resolutions)."""
    f = _series("f", f)
    p = _series("p", p, length=len(f))
    fmax = _real("fmax", fmax, "a frequency in Hz", 0.0)
    count = _integer("count", count, "a whole number of peaks >= 1", 1, 10 ** 6)
    df = f[1] - f[0] if len(f) > 1 else 1.0
    sel = (f >= 2 * df) & (f <= fmax)
    idx, _ = signal.find_peaks(np.where(sel, p, 0.0), distance=4)
    idx = sorted((i for i in idx if sel[i]), key=lambda i: -p[i])[:count]
    return [{"frequency_hz": float(f[i]), "psd_N2_per_hz": float(p[i]),
             "amplitude_N": float(math.sqrt(2.0 * np.sum(p[max(0, i - 3):i + 4]) * df))} for i in idx]


# --------------------------------------------------------------------------------------------
# The simulated run
# --------------------------------------------------------------------------------------------
def _profile(record, speed_profile):
    """(stations m, speeds m/s) of the profile, and where it comes from."""
    if speed_profile is None:
        if record is None or record.speed_mps is None:
            if record is not None and record.time_s is not None:
                mid = 0.5 * (record.time_s[1:] + record.time_s[:-1])
                v = np.diff(record.station_m) / np.diff(record.time_s)
                x = np.interp(mid, record.time_s, record.station_m)
                return x, v, "the record's stations against its times"
            raise SceneError("speed_profile = None rejected: the record has no speed or time column; allowed a "
                             "speed in km/h or a profile (stations m, speeds km/h)", field="speed_profile",
                             value="None", allowed="a speed in km/h or a profile (stations m, speeds km/h)")
        return record.station_m, record.speed_mps, "the record's speed column"
    if isinstance(speed_profile, (int, float, np.floating, np.integer)) and not isinstance(speed_profile, bool):
        v = _real("speed_profile", speed_profile, "a speed in km/h, 1e-6 to 540", 1e-6, 540.0)
        return np.array([0.0]), np.array([v / 3.6]), f"{v:g} km/h throughout"
    try:
        x, v = (np.asarray(a, dtype=float) for a in speed_profile)
    except (TypeError, ValueError):
        raise SceneError(f"speed_profile = {_shown(speed_profile)} rejected: allowed a speed in km/h or a pair "
                         "(stations m, speeds km/h)", field="speed_profile", value=_shown(speed_profile),
                         allowed="a speed in km/h or a pair (stations m, speeds km/h)") from None
    if (x.ndim != 1 or x.shape != v.shape or len(x) < 1 or not np.all(np.isfinite(x)) or not np.all(np.isfinite(v))
            or np.any(np.diff(x) <= 0) or np.any(v <= 0) or np.any(v > 540)):
        raise SceneError("speed_profile rejected: allowed increasing stations (m) and speeds 0 < v <= 540 km/h of "
                         "the same length", field="speed_profile", value=_shown(speed_profile),
                         allowed="increasing stations (m) and speeds 0 < v <= 540 km/h")
    return x, v / 3.6, "the given profile"


def read_speed_profile(path):
    """A speed profile CSV (station_m, speed_kmh) as (stations m, speeds km/h)."""
    path = _path("speed_profile", path, "a CSV path with columns station_m, speed_kmh")
    try:
        t = pd.read_csv(path)
        x, v = t["station_m"].to_numpy(float), t["speed_kmh"].to_numpy(float)
    except (OSError, KeyError, ValueError, pd.errors.ParserError, pd.errors.EmptyDataError) as e:
        raise SceneError(f"speed profile {path} rejected ({e}); allowed a CSV with columns station_m, speed_kmh",
                         field="speed_profile", value=path, allowed="a CSV with columns station_m, speed_kmh") from None
    try:
        _profile(None, (x, v))  # the same checks as a profile given in code
    except SceneError as e:
        raise SceneError(f"speed profile {path} rejected: {e.allowed}", field="speed_profile", value=path,
                         allowed=e.allowed) from None
    return x, v


class SimulatedRun:
    """The scene's pass driven by a speed profile, at every step: time_s, speed_mps, and per
    pantograph position_m, force_N (as computed), measured_N (the measuring pantograph's view at
    the sensor bandwidth), head_m; uplift_m per steady arm (station, series); stats (stats.json)."""

    def __init__(self, **kw):
        self.__dict__.update(kw)

    def write_files(self, directory):
        """The pass's own files (simulate_pass --out's; scripts/pass_report draws them)."""
        self.simulation.write_files(directory)


def simulate_run(scene, record=None, overrides=None, speed_profile=None, sensor_bandwidth_hz=None,
                 pantograph=None, max_steps=2e7):
    """Runs the scene with the train's speed following the profile: before every step the train's
    speed is set (Simulation.set_speed, no acceleration limit) to the profile at the station of
    `pantograph` (default: the record's station_of, else the first), linear between the profile's
    stations and held beyond its ends. The measuring pantograph's bandwidth is the record's (or
    sensor_bandwidth_hz). Refuses a record's pantograph or support the scene lacks."""
    if record is not None and not isinstance(record, Record):
        _refuse("record", record, "None or a Record (read_record's)")
    max_steps = _real("max_steps", max_steps, "a number of steps >= 1", 1.0)
    ov = _override_list(overrides)
    px, pv, source = _profile(record, speed_profile)
    bw = sensor_bandwidth_hz if sensor_bandwidth_hz is not None else (record.bandwidth_hz if record else None)
    if bw is not None:
        bw = _real("sensor_bandwidth_hz", bw, "a bandwidth in Hz > 0", 1e-6)
        ov = ov + [f"output.sensor_bandwidth={bw!r}"]
    # The probe (the pantographs' names and places) at the profile's fastest speed: the scene's
    # limit on it (below the contact wire's wave speed) is the profile's, named by where the profile
    # comes from rather than by the scene's train.speed_kmh.
    fastest = 3.6 * float(np.max(pv))
    try:
        probe = Simulation(scene, ov + ["train.speed=null", f"train.speed_kmh={fastest!r}"], sample_rate=0)
    except SceneError as e:
        if e.field == "train.speed_kmh":
            if speed_profile is None:
                column = record.columns.get(("speed", None), "station_m")
                raise RecordError("speed_profile", record.path, column, f"{fastest:.4g} km/h", e.allowed,
                                  "faster than the scene allows (" + source + ")") from None
            raise SceneError(f"speed_profile = {_shown(speed_profile)} rejected: {fastest:.4g} km/h is faster than "
                             f"the scene allows; allowed {e.allowed}", field="speed_profile",
                             value=_shown(speed_profile), allowed=e.allowed) from None
        if bw is None or e.field != "output.sensor_bandwidth":
            raise
        allowed = f"the measuring pantograph's bandwidth, output.sensor_bandwidth's {e.allowed}"
        if sensor_bandwidth_hz is None:
            raise RecordError("metadata", record.path, "bandwidth_hz", f"{bw:g}", allowed,
                              "beyond what the simulated measuring pantograph takes") from None
        raise SceneError(f"sensor_bandwidth_hz = {bw:g} rejected: allowed {allowed}", field="sensor_bandwidth_hz",
                         value=f"{bw:g}", allowed=allowed) from None
    names = list(probe.pantograph_names)
    if record is not None:
        for name in record.force_N:
            if name not in names:
                raise RecordError("unknown_pantograph", record.path, record.columns[("force", name)], name,
                                  "a pantograph of the scene: " + ", ".join(names), "the scene has no such pantograph")
    ref = pantograph if pantograph is not None else (record.station_of if record is not None else names[0])
    if ref not in names:
        raise SceneError(f"pantograph = {ref!r} rejected: allowed one of {', '.join(names)}", field="pantograph",
                         value=repr(ref), allowed=", ".join(names))
    i = names.index(ref)
    x0 = probe.pantograph_state(i)["position_m"]
    v0 = float(np.interp(x0, px, pv))
    sim = Simulation(scene, ov + ["train.speed=null", f"train.speed_kmh={3.6 * v0!r}"], sample_rate=0)
    speeds = [sim.speed]
    applied_x, applied_v = [], []  # the speed set at each station (the profile as the train met it)
    steps = 0
    while not sim.finished():
        x = sim.pantograph_state(i)["position_m"]
        v = float(np.interp(x, px, pv))
        sim.set_speed(v)
        if sim.step(1) == 0:
            break
        applied_x.append(x)
        applied_v.append(v)
        speeds.append(sim.speed)
        steps += 1
        if steps > max_steps:
            raise SceneError(f"max_steps = {max_steps:g} rejected: the pass takes longer; allowed more steps, or a "
                             "faster profile", field="max_steps",
                             value=repr(max_steps), allowed="more steps, or a faster profile")
    series = sim.series()
    with tempfile.TemporaryDirectory(prefix="catenary_sim_measure_") as d:
        sim.write_files(d)
        processed = pd.read_csv(os.path.join(d, "force_processed.csv"))
        with open(os.path.join(d, "stats.json"), encoding="utf-8") as f:
            stats = json.load(f)
    n = len(series["time_s"])
    arms = sorted(sim.steady_arms, key=lambda a: a["station_m"])
    ucols = [c for c in series if c.startswith("uplift_steady_arm")]
    uplift = [(a["station_m"], np.asarray(series[c])) for a, c in zip(arms, ucols)] if len(arms) == len(ucols) else []
    return SimulatedRun(simulation=sim, scene=scene, overrides=ov, reference=ref, time_s=np.asarray(series["time_s"]),
                        speed_mps=np.asarray(speeds[:n]), profile=(px, pv), profile_source=source,
                        applied=(np.asarray(applied_x), np.asarray(applied_v)),
                        position_m={p: np.asarray(series[p + "_position_m"]) for p in names},
                        force_N={p: np.asarray(series[p + "_force_N"]) for p in names},
                        measured_N={p: processed[p + "_force_measured_N"].to_numpy(float) for p in names},
                        head_m={p: np.asarray(series[p + "_head_displacement_m"]) for p in names
                                if p + "_head_displacement_m" in series},
                        uplift_m=uplift, stats=stats, dt=sim.dt, names=names)


# --------------------------------------------------------------------------------------------
# The comparison
# --------------------------------------------------------------------------------------------
def _tolerance(tolerances, name, owner):
    """The user's tolerance for a quantity of a pantograph or support: 'owner.name' before 'name';
    a number (the quantity's unit) or 'P%' of the record's value."""
    if not tolerances:
        return None
    for key in (f"{owner}.{name}", name):
        if key in tolerances:
            return tolerances[key]
    return None


def _check_tolerances(tolerances, record):
    """{key: (number, percent)} of the user's tolerances, each refused by name unless it names a
    quantity the comparison has a row of, for an owner (pantograph or support) the record has."""
    if tolerances is None:
        return {}
    if not isinstance(tolerances, dict):
        raise SceneError(f"tolerances = {_shown(tolerances)} rejected: allowed a map NAME: tolerance",
                         field="tolerances", value=_shown(tolerances), allowed="a map NAME: tolerance")
    # The rows the comparison forms: per pantograph its statistics and differences (the head's
    # with a head column), per support the uplift.
    rows = {p: STATISTICS + DIFFERENCES + (HEAD if p in record.head_m else ()) for p in record.force_N}
    rows.update({name: UPLIFT for name in record.uplift_m})
    present = "; ".join(f"{o}: {', '.join(q)}" for o, q in rows.items())
    out = {}
    for key, v in tolerances.items():
        name = str(key).split(".")[-1]
        owner = str(key)[:-len(name) - 1] if "." in str(key) else None
        allowed = ("NAME or OWNER.NAME with NAME one of " + ", ".join(TOLERANCE_NAMES) + " and OWNER a pantograph or "
                   "support of the record (" + ", ".join(rows) + ")")
        if name not in TOLERANCE_NAMES or (owner is not None and owner not in rows):
            raise SceneError(f"tolerances key {key!r} rejected: allowed {allowed}", field="tolerances",
                             value=repr(key), allowed=allowed)
        if not any(name in q for o, q in rows.items() if owner is None or o == owner):
            needs = {**{n: " (it needs a head column)" for n in HEAD}, **{n: " (it needs supports)" for n in UPLIFT}}
            raise SceneError(f"tolerances key {key!r} rejected: {owner or 'the record'} has no {name} to compare"
                             f"{needs.get(name, '')}; allowed a quantity the comparison has: {present}",
                             field="tolerances", value=repr(key), allowed=present)
        text = str(v).strip()
        m = re.fullmatch(r"([0-9.eE+-]+)\s*(%?)", text)
        try:
            num = float(m.group(1)) if m else math.nan
        except ValueError:
            num = math.nan
        if isinstance(v, bool) or not (math.isfinite(num) and num >= 0):
            raise SceneError(f"tolerances['{key}'] = {v!r} rejected: allowed a number >= 0 in the quantity's unit, "
                             "or 'P%' of the record's value", field=f"tolerances.{key}", value=repr(v),
                             allowed="a number >= 0, or 'P%'")
        if m.group(2) and name in DIFFERENCES:
            unit = name.rsplit("_", 1)[1]
            raise SceneError(f"tolerances['{key}'] = {v!r} rejected: {name} is itself a difference of the two sides, "
                             f"with no record's value to take a share of; allowed a number >= 0 in {unit}",
                             field=f"tolerances.{key}", value=repr(v), allowed=f"a number >= 0 in {unit}")
        out[str(key)] = (num, bool(m.group(2)))
    return out


def _row(quantity, owner, unit, rec, sim, tol, difference=False):
    """One line of the table: the deviation (simulated - record) against the tolerance; for a
    quantity that is itself a difference (rms, max) the value against it."""
    row = {"quantity": quantity, "of": owner, "unit": unit, "record": rec, "simulated": sim, "deviation": None,
           "relative_deviation": None, "tolerance": None, "within": None}
    if difference:
        row["deviation"] = sim
    elif rec is not None and sim is not None:
        row["deviation"] = sim - rec
        if rec != 0:
            row["relative_deviation"] = (sim - rec) / abs(rec)
    if tol is not None and row["deviation"] is not None:
        num, percent = tol
        if percent and not difference:
            limit = num / 100.0 * abs(rec)
            row["tolerance"] = f"{num:g}% = {limit:.4g}"
        else:
            limit = num
            row["tolerance"] = f"{num:g}"
        row["within"] = bool(abs(row["deviation"]) <= limit)
    return row


class Comparison:
    """A record beside its simulated run: rows (the statistics table), series (pandas, per record
    row within the simulated run), spectra (pandas), settings, and the two sides' inputs."""

    def __init__(self, **kw):
        self.__dict__.update(kw)

    def summary(self):
        """The comparison as comparison.json holds it."""
        return {"record": self.record.path, "scene": self.scene_name, "settings": self.settings, "rows": self.rows,
                "peaks": self.peaks, "within": self.within(), "simulated_stats": self.run.stats}

    def within(self):
        """True when every tolerance given holds, False when one does not, None without tolerances."""
        marks = [r["within"] for r in self.rows if r["within"] is not None]
        return None if not marks else all(marks)

    def write(self, directory, report=True, pass_files=True):
        """Writes DIR/comparison.json, statistics.csv, series.csv, spectra.csv, with report=True
        report.html and report_*.png, with pass_files=True the simulated pass's own files in
        DIR/simulated/. Everything is made first in a temporary directory beside DIR and moved into
        place file by file (each whole); a DIR that does not exist appears whole or not at all."""
        from . import measurement_report
        target = _path("directory", directory, "a directory path (str or os.PathLike)")
        if not target:
            _refuse("directory", directory, "a directory path (str or os.PathLike)", "an empty path")
        for name, flag in (("report", report), ("pass_files", pass_files)):
            if not isinstance(flag, (bool, np.bool_)):
                _refuse(name, flag, "True or False")
        target = os.path.abspath(target)
        if os.path.lexists(target) and not os.path.isdir(target):
            raise SceneError(f"directory = {target!r} rejected: it exists and is not a directory; allowed a "
                             "directory (made if absent)", field="directory", value=repr(target),
                             allowed="a directory (made if absent)")
        parent = os.path.dirname(target)
        os.makedirs(parent, exist_ok=True)
        files = {"comparison.json": json.dumps(self.summary(), indent=2, allow_nan=False).encode() + b"\n",
                 "statistics.csv": pd.DataFrame(self.rows).to_csv(index=False).encode(),
                 "series.csv": self.series.to_csv(index=False, float_format="%.10g").encode(),
                 "spectra.csv": self.spectra.to_csv(index=False, float_format="%.10g").encode()}
        if report:
            files.update(measurement_report.build(self))
        stage = tempfile.mkdtemp(prefix="." + os.path.basename(target) + ".", dir=parent)
        try:
            for name, data in files.items():
                with open(os.path.join(stage, name), "wb") as f:
                    f.write(data)
            if pass_files:
                self.run.write_files(os.path.join(stage, "simulated"))
            if not os.path.exists(target):
                os.rename(stage, target)
                os.chmod(target, 0o777 & ~_files.umask())
                return target
            # Into an existing directory: every place checked before anything moves, so that a
            # directory where a file goes (or a file where a directory goes) moves nothing.
            moves = []
            for top, dirs, names in os.walk(stage):
                rel = os.path.relpath(top, stage)
                for name in dirs:
                    there = os.path.normpath(os.path.join(target, rel, name))
                    if os.path.lexists(there) and not os.path.isdir(there):
                        _refuse("directory", directory, "a directory whose outputs' places hold no other kind of "
                                "entry", f"{there} is not a directory")
                for name in names:
                    there = os.path.normpath(os.path.join(target, rel, name))
                    if os.path.isdir(there):
                        _refuse("directory", directory, "a directory whose outputs' places hold no other kind of "
                                "entry", f"{there} is a directory")
                    moves.append((os.path.join(top, name), there))
            try:
                for source, there in moves:
                    os.makedirs(os.path.dirname(there), exist_ok=True)
                    os.replace(source, there)
            except OSError as e:
                raise SceneError(f"directory = {target!r} rejected: cannot be written ({e.strerror or e}); allowed "
                                 "a writable directory", field="directory", value=repr(target),
                                 allowed="a writable directory") from None
        finally:
            shutil.rmtree(stage, ignore_errors=True)
        return target


def least_band_hz(rows, sample_rate_hz):
    """The lowest cutoff or bandwidth a record of `rows` samples at sample_rate_hz is filtered with:
    one period within its duration (rows / sample_rate_hz). A filter whose period is longer has no
    whole period of the record to act on; its edge padding, not the record, makes the result. At
    least 0.1 Hz, the statistics' filter's least cutoff (output.filter_cutoff's)."""
    return max(sample_rate_hz / rows, 0.1)


def _cutoff(cutoff_hz, record, stats=None):
    """The analysis low-pass in Hz and where it comes from; refused by name below the record's
    least band. Without stats (before the pass) the scene's cutoff is not yet known: None."""
    least = least_band_hz(len(record.station_m), record.sample_rate_hz)
    duration = f"at least {least:.4g} Hz for this record ({len(record.station_m)} rows at " \
               f"{record.sample_rate_hz:g} Hz, {1.0 / least:.4g} s)"
    if isinstance(cutoff_hz, str) and cutoff_hz == "bandwidth":
        return record.bandwidth_hz, "the record's bandwidth"  # read_record checks it against the duration
    if cutoff_hz is None or (isinstance(cutoff_hz, str) and cutoff_hz == "scene"):
        if stats is None:
            return None, "the scene's output.filter_cutoff"
        fc = float(stats["filter_cutoff_hz"])
        if fc < least:
            raise SceneError(f"cutoff_hz = 'scene' rejected: the scene's output.filter_cutoff, {fc:g} Hz, has a "
                             f"period longer than the record; allowed {duration}, or 'bandwidth'",
                             field="cutoff_hz", value="'scene'", allowed=duration)
        return fc, "the scene's output.filter_cutoff"
    fc = _real("cutoff_hz", cutoff_hz, "a cutoff of at least 0.1 Hz, 'scene' or 'bandwidth'", 0.1)
    if fc < least:
        raise SceneError(f"cutoff_hz = {fc:g} rejected: its period exceeds the record's duration; allowed {duration}",
                         field="cutoff_hz", value=f"{fc:g}", allowed=duration)
    return fc, "given"


def _span(supports, section):
    """The span length of the scene's line at the section (m): the mean of the spans within it,
    else (a section inside one span) the span of the line around the section's middle; None for a
    line of fewer than two supports."""
    within = np.diff([x for x in supports if section[0] - 1e-6 <= x <= section[1] + 1e-6])
    if len(within):
        return float(np.mean(within))
    if len(supports) < 2:
        return None
    k = int(np.searchsorted(supports, 0.5 * (section[0] + section[1])))
    k = min(max(k, 1), len(supports) - 1)  # beyond the line's ends: its end span
    return float(supports[k] - supports[k - 1])


def compare(scene, record, overrides=None, speed_profile=None, cutoff_hz=None, tolerances=None, meta=None):
    """Simulates the record's run on the scene and compares the two (docs/measured_records.md).

    scene: a path or dict; record: a Record or a CSV path (meta: its side YAML); overrides as for
    Simulation; speed_profile: None (the record's), a speed in km/h, or (stations m, speeds km/h);
    cutoff_hz: the analysis low-pass applied to both sides, None or 'scene' (output.filter_cutoff),
    'bandwidth' (the record's) or Hz; tolerances: {NAME or OWNER.NAME: number or 'P%'}."""
    if not isinstance(record, Record):
        record = read_record(record, meta)
    tol = _check_tolerances(tolerances, record)
    _cutoff(cutoff_hz, record)
    run = simulate_run(scene, record, overrides, speed_profile)
    stats = run.stats
    fc, fc_source = _cutoff(cutoff_hz, record, stats)
    fs = record.sample_rate_hz
    ref = record.station_of
    pos = run.position_m[ref]
    travel = (float(pos[0]), float(pos[-1]))
    section = record.section_m
    if section is None:
        # The scene's analysis section where both the pantograph's run and the record reach (a
        # pantograph behind the train's front starts inside the line, as the core counts it).
        a0, a1 = stats["analysis_section_m"]
        section = (max(a0, travel[0], record.station_m[0]), min(a1, travel[1], record.station_m[-1]))
        if not section[0] < section[1]:
            section = (a0, a1)
    if not (travel[0] <= section[0] < section[1] <= travel[1]):
        raise RecordError("section_outside_line", record.path, "section_m",
                          f"[{section[0] + record.station_origin_m:g}, {section[1] + record.station_origin_m:g}]",
                          f"within the scene's line as the pantograph runs it, "
                          f"[{travel[0] + record.station_origin_m:g}, {travel[1] + record.station_origin_m:g}] m "
                          "in the record's stations", "outside the scene's line")
    if not (record.station_m[0] <= section[0] and section[1] <= record.station_m[-1]):
        raise RecordError("section_outside_line", record.path, "section_m",
                          f"[{section[0] + record.station_origin_m:g}, {section[1] + record.station_origin_m:g}]",
                          f"within the record's stations [{record.station_m[0] + record.station_origin_m:g}, "
                          f"{record.station_m[-1] + record.station_origin_m:g}] m (declare section_m)",
                          "the record does not cover the analysis section")
    arms = run.uplift_m
    for name, x in record.support_station_m.items():
        near = min(arms, key=lambda a: abs(a[0] - x), default=None)
        if near is None or abs(near[0] - x) > 0.5:
            raise RecordError("unknown_support", record.path, f"supports.{name}", f"{x + record.station_origin_m:g}",
                              "the station of a steady arm of the scene within 0.5 m: " +
                              ", ".join(f"{a[0] + record.station_origin_m:g}" for a in arms[:12]) +
                              (" ..." if len(arms) > 12 else ""), "no steady arm there")
    # Both sides on the record's rows: the simulated time at which the reference pantograph is at
    # each station, and everything simulated at that time.
    keep = (record.station_m >= travel[0]) & (record.station_m <= travel[1])
    station = record.station_m[keep]
    t_at = np.interp(station, pos, run.time_s)
    rec_view = {p: f[keep] for p, f in record.force_N.items()}
    sim_view = {p: np.interp(t_at, run.time_s, run.measured_N[p]) for p in record.force_N}
    rec_f = {p: lowpass(v, fs, fc) for p, v in rec_view.items()}
    sim_f = {p: lowpass(v, fs, fc) for p, v in sim_view.items()}
    inside = (station >= section[0]) & (station <= section[1])
    if inside.sum() < MIN_SECTION_ROWS:
        step = float(np.median(np.diff(record.station_m)))
        raise RecordError("short_section", record.path, "section_m",
                          f"[{section[0] + record.station_origin_m:g}, {section[1] + record.station_origin_m:g}]",
                          f"a section holding at least {MIN_SECTION_ROWS} rows (at least "
                          f"{(MIN_SECTION_ROWS - 1) * step:.3g} m at the record's {step:.3g} m between rows)", f"it holds {int(inside.sum())} of the record's "
                          "rows" + ("" if record.section_m is not None else
                                    " (the scene's analysis section where the record reaches: declare section_m)"))
    columns = {"station_m": station + record.station_origin_m, "simulated_time_s": t_at,
               "simulated_speed_kmh": 3.6 * np.interp(t_at, run.time_s, run.speed_mps),
               "profile_speed_kmh": 3.6 * np.interp(station, *run.profile), "in_section": inside.astype(int)}
    if record.speed_mps is not None:
        columns["record_speed_kmh"] = 3.6 * record.speed_mps[keep]
    rows, peaks = [], {}
    spectra = []
    supports = sorted(x for x in stats.get("support_stations_m", []))
    mean_span = _span(supports, section)
    v_mean = float(np.mean(np.interp(t_at[inside], run.time_s, run.speed_mps)))
    # Without a span (a line of fewer than two supports) one segment: the whole section.
    segment_s = 8.0 * mean_span / v_mean if mean_span else float(inside.sum()) / fs
    for p in record.force_N:
        a = section_statistics(rec_f[p], inside)
        b = section_statistics(sim_f[p], inside)
        for name in STATISTICS:
            rows.append(_row(name, p, "%" if name.endswith("percent") else "N", a[name], b[name],
                             _tolerance(tol, name, p)))
        diff = sim_f[p][inside] - rec_f[p][inside]
        rows.append(_row("force_rms_difference_N", p, "N", None, float(np.sqrt(np.mean(diff ** 2))),
                         _tolerance(tol, "force_rms_difference_N", p), True))
        rows.append(_row("force_max_abs_difference_N", p, "N", None, float(np.max(np.abs(diff))),
                         _tolerance(tol, "force_max_abs_difference_N", p), True))
        fr, pr = welch_spectrum(rec_view[p][inside], fs, segment_s)
        _, ps = welch_spectrum(sim_view[p][inside], fs, segment_s)
        band = (fr > 0) & (fr <= min(fc, record.bandwidth_hz)) & (pr > 0) & (ps > 0)
        db = float(np.sqrt(np.mean((10 * np.log10(ps[band] / pr[band])) ** 2))) if band.any() else None
        rows.append(_row("spectrum_rms_difference_dB", p, "dB", None, db,
                         _tolerance(tol, "spectrum_rms_difference_dB", p), True))
        fmax = min(fc, record.bandwidth_hz)
        peaks[p] = {"record": spectral_peaks(fr, pr, fmax), "simulated": spectral_peaks(fr, ps, fmax)}
        spectra.append(pd.DataFrame({"pantograph": p, "frequency_hz": fr, "record_psd_N2_per_hz": pr,
                                     "simulated_psd_N2_per_hz": ps}))
        columns[f"record_force_{p}_N"] = rec_view[p]
        columns[f"simulated_force_{p}_N"] = sim_view[p]
        columns[f"record_force_{p}_filtered_N"] = rec_f[p]
        columns[f"simulated_force_{p}_filtered_N"] = sim_f[p]
        if p in record.head_m:
            rh = record.head_m[p][keep]
            sh = np.interp(t_at, run.time_s, run.head_m[p])
            for name, fn in (("head_std_m", np.std), ("head_range_m", np.ptp)):
                rows.append(_row(name, p, "m", float(fn(rh[inside])), float(fn(sh[inside])), _tolerance(tol, name, p)))
            columns[f"record_head_{p}_m"] = rh
            columns[f"simulated_head_{p}_m"] = sh
    # Steady arms: the largest uplift while a pantograph is within half the shorter adjacent span
    # of the arm (the core's reach), on both sides at the record's rows.
    at_rows = [np.interp(t_at, run.time_s, run.position_m[q]) for q in run.names]
    for name, x in record.support_station_m.items():
        sx, su = min(arms, key=lambda a: abs(a[0] - x))
        k = int(np.searchsorted(supports, sx - 1e-6))
        left = sx - supports[k - 1] if k > 0 else math.inf
        right = supports[k + 1] - sx if k + 1 < len(supports) else math.inf
        reach = 0.5 * min(left, right)
        near = np.any([np.abs(xq - sx) <= reach for xq in at_rows], axis=0)
        ru = record.uplift_m[name][keep]
        su_at = np.interp(t_at, run.time_s, su)
        rows.append(_row("max_uplift_m", name, "m", float(np.max(ru[near])) if near.any() else None,
                         float(np.max(su_at[near])) if near.any() else None, _tolerance(tol, "max_uplift_m", name)))
        columns[f"record_uplift_{name}_m"] = ru
        columns[f"simulated_uplift_{name}_m"] = su_at
    settings = {"cutoff_hz": fc, "cutoff_source": fc_source, "record_bandwidth_hz": record.bandwidth_hz,
                "record_sample_rate_hz": fs, "section_m": [section[0] + record.station_origin_m,
                                                          section[1] + record.station_origin_m],
                "station_origin_m": record.station_origin_m, "station_of": ref,
                "speed_profile": run.profile_source, "welch_segment_s": segment_s,
                "span_passing_hz": v_mean / mean_span if mean_span else None, "mean_speed_kmh": 3.6 * v_mean,
                "rows_compared": int(keep.sum()), "rows_in_section": int(inside.sum()),
                "tolerances": {k: (f"{v[0]:g}%" if v[1] else v[0]) for k, v in tol.items()},
                "overrides": run.overrides}
    name = scene if isinstance(scene, dict) else os.fspath(scene)
    return Comparison(record=record, run=run, rows=rows, peaks=peaks, settings=settings,
                      series=pd.DataFrame(columns), spectra=pd.concat(spectra, ignore_index=True),
                      scene_name=name.get("name", "scene") if isinstance(name, dict) else name,
                      support_stations_m=[x + record.station_origin_m for x in supports])


# --------------------------------------------------------------------------------------------
# A record from a simulated pass (the worked example and the tests)
# --------------------------------------------------------------------------------------------
DECIMALS = {"station_m": 6, "time_s": 6, "speed_kmh": 6, "force": 4, "uplift_mm": 4, "head_mm": 4}


def noise_after_filters(noise_std, fs, cutoffs, n=1 << 16):
    """The std of white noise of noise_std at fs after the zero-phase low-passes at `cutoffs`:
    sqrt of sigma^2 x the mean of prod |H_k(f)|^4 over [0, fs/2] (filtfilt squares |H|)."""
    noise_std = _real("noise_std", noise_std, "a noise std >= 0", 0.0)
    fs = _real("fs", fs, "a sample rate in Hz > 0", 1e-300)
    if isinstance(cutoffs, (str, bytes)) or not isinstance(cutoffs, Iterable):
        _refuse("cutoffs", cutoffs, "a sequence of cutoffs in Hz > 0")
    cutoffs = [_real(f"cutoffs[{k}]", c, "a cutoff in Hz > 0", 1e-300) for k, c in enumerate(cutoffs)]
    n = _integer("n", n, "an integer number of frequencies >= 2", 2, 1 << 26)
    f = np.linspace(0.0, 0.5 * fs, n)
    gain = np.ones_like(f)
    for fc in cutoffs:
        if fc < 0.5 * fs:
            _, h = signal.sosfreqz(signal.butter(4, fc, fs=fs, output="sos"), worN=f, fs=fs)
            gain *= np.abs(h) ** 4
    return noise_std * math.sqrt(float(np.mean(gain)))


def synthesise_record(scene, path, overrides=None, speed_profile=300.0, sample_rate_hz=200.0, bandwidth_hz=20.0,
                      noise_std_N=0.0, seed=0, supports="section", head=True, station_origin_m=0.0):
    """A record as a measuring run would write it, from a simulated pass: the core's measuring
    pantograph's view at bandwidth_hz (every pantograph), sampled at sample_rate_hz, with white
    noise of noise_std_N per sample passed through the same measuring filter (zero-phase
    Butterworth, as the core's sensor model), the speed, the head displacement and the uplift of
    the steady arms ("section": those in the scene's analysis section, named A1, A2, ...; None:
    none). Writes PATH (CSV) and its side YAML (PATH with .yaml) once every argument and the
    record read back are checked, each whole; a refusal leaves neither. Returns the Record."""
    path, side = _record_paths(path)
    fs = _real("sample_rate_hz", sample_rate_hz, f"a sample rate in Hz, {MIN_RECORD_RATE_HZ:g} to "
               f"{MAX_RECORD_RATE_HZ:g} (the time column's {10.0 ** -DECIMALS['time_s']:g} s resolution)",
               MIN_RECORD_RATE_HZ, MAX_RECORD_RATE_HZ)
    bw = _real("bandwidth_hz", bandwidth_hz, "a bandwidth in Hz > 0", 1e-3, 1e7)
    sigma = _real("noise_std_N", noise_std_N, "a noise std in N >= 0", 0.0, 1e4)
    seed = _integer("seed", seed, "an integer >= 0", 0, 2 ** 63 - 1)
    origin = _real("station_origin_m", station_origin_m, "a station in m", -1e7, 1e7)
    if not (supports is None or (isinstance(supports, str) and supports == "section")):
        _refuse("supports", supports, "'section' (the steady arms of the analysis section) or None (no uplift "
                "columns)")
    if not isinstance(head, (bool, np.bool_)):
        _refuse("head", head, "True or False (head displacement columns or none)")
    try:
        run = simulate_run(scene, None, overrides, speed_profile, sensor_bandwidth_hz=bw)
    except SceneError as e:
        if e.field != "sensor_bandwidth_hz":
            raise
        raise SceneError(str(e).replace("sensor_bandwidth_hz", "bandwidth_hz", 1), field="bandwidth_hz",
                         value=e.value, allowed=e.allowed) from None
    ref = run.reference
    t = np.arange(run.time_s[0], run.time_s[-1], 1.0 / fs)
    if len(t) < 3:
        duration = float(run.time_s[-1] - run.time_s[0])
        raise SceneError(f"sample_rate_hz = {fs:g} rejected: the pass of {duration:.4g} s gives {len(t)} "
                         f"row(s); allowed at least {3.0 / duration:.4g} Hz (3 rows)", field="sample_rate_hz",
                         value=f"{fs:g}", allowed=f"at least {3.0 / duration:.4g} Hz")
    least = least_band_hz(len(t), fs)
    if bw < least:
        raise SceneError(f"bandwidth_hz = {bw:g} rejected: its period exceeds the record's duration; allowed at "
                         f"least {least:.4g} Hz for {len(t)} rows at {fs:g} Hz", field="bandwidth_hz",
                         value=f"{bw:g}", allowed=f"at least {least:.4g} Hz")
    station = np.interp(t, run.time_s, run.position_m[ref])
    cols = {"station_m": np.round(station + origin, DECIMALS["station_m"]),
            "time_s": np.round(t - t[0], DECIMALS["time_s"]),
            # The speed the train was set to at each station: a record's speed column drives the
            # comparison's run the same way, station by station.
            "speed_kmh": np.round(3.6 * np.interp(station, *run.applied), DECIMALS["speed_kmh"])}
    rng = np.random.default_rng(seed)
    for p in run.names:
        f = np.interp(t, run.time_s, run.measured_N[p])
        if sigma > 0:
            f = f + lowpass(rng.normal(0.0, sigma, len(t)), fs, bw)
        cols[f"force_{p}_N"] = np.round(f, DECIMALS["force"])
        if head and p in run.head_m:
            cols[f"head_{p}_mm"] = np.round(1e3 * np.interp(t, run.time_s, run.head_m[p]), DECIMALS["head_mm"])
    meta = {"name": f"synthesised from {scene if not isinstance(scene, dict) else scene.get('name', 'a scene')}",
            "sample_rate_hz": fs, "bandwidth_hz": bw, "pantographs": list(run.names), "station_of": ref,
            "station_origin_m": origin}
    if supports == "section":
        a0, a1 = run.stats["analysis_section_m"]
        chosen = [(f"A{k + 1}", x, u) for k, (x, u) in enumerate(run.uplift_m) if a0 <= x <= a1]
        meta["supports"] = {}
        for name, x, u in chosen:
            cols[f"uplift_{name}_mm"] = np.round(1e3 * np.interp(t, run.time_s, u), DECIMALS["uplift_mm"])
            meta["supports"][name] = float(x + origin)
    table = pd.DataFrame(cols)
    # Both files are written beside their places and read back as a record before either is
    # moved into place: a record that would be refused, or a write that fails, leaves nothing.
    staged = []
    try:
        for target, text in ((path, table.to_csv(index=False, float_format="%.6f")),
                             (side, yaml.safe_dump(meta, sort_keys=False))):
            staged.append((_files.stage(target, text), target))
        try:
            record = read_record(staged[0][0], meta=staged[1][0])
        except RecordError as e:
            # What the record's checks refuse comes of the arguments that made it (a noise that
            # carries the force beyond a plausible record's), not of the staged file it names.
            raise SceneError(f"the synthesised record would be refused ({e.kind}: {e.field} = {e.value}, allowed "
                             f"{e.allowed}); check noise_std_N = {sigma:g}, sample_rate_hz and the scene's forces",
                             field="noise_std_N", value=f"{sigma:g}", allowed=e.allowed) from None
        new_side = not os.path.lexists(side)
        os.replace(staged[1][0], side)
        try:
            os.replace(staged[0][0], path)
        except OSError:
            if new_side:
                os.remove(side)
            raise
    except OSError as e:
        raise SceneError(f"path = {path!r} rejected: cannot be written ({e.strerror or e}); allowed a CSV path in a "
                         "writable directory", field="path", value=repr(path),
                         allowed="a CSV path in a writable directory") from None
    finally:
        for tmp, _target in staged:
            if os.path.exists(tmp):
                os.remove(tmp)
    record.path = path
    return record


# The synthesised record's sample rate: at 1e5 Hz a row's interval is 10 us, which the time
# column's rounding to 1 us moves by at most 10 %, the reader's agreement with the declared rate.
MIN_RECORD_RATE_HZ, MAX_RECORD_RATE_HZ = 1e-3, 1e5


def _record_paths(path):
    """A synthesised record's CSV path and its side YAML's, refused unless PATH ends in .csv and
    both can be made in an existing, writable directory."""
    path = os.fspath(_path("path", path, "a CSV file path ending in .csv"))

    def refuse(why):
        _refuse("path", path, "a path ending in .csv in an existing, writable directory", why)

    stem, ext = os.path.splitext(path)
    if ext.lower() != ".csv" or not os.path.basename(stem):
        refuse("not a .csv file name (the metadata goes beside it as NAME.yaml)")
    side = stem + ".yaml"
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        refuse(f"its directory {directory} does not exist")
    if not os.access(directory, os.W_OK | os.X_OK):
        refuse(f"its directory {directory} is not writable")
    for p in (path, side):
        if os.path.isdir(p):
            refuse(f"{p} is a directory")
    return path, side
