"""Fit a lumped pantograph chain (eq. 9: masses head first, each on a spring and a damper to the
mass below, the last to the roof) to a measured head FRF (receptance X/F against frequency), as
laboratories identify a pantograph model from its frequency response.

    fit = fit_chain(freq_hz, receptance, masses=2)
    fit.masses, fit.stiffness, fit.damping, fit.residual_rms, fit.std

The residual is relative, (H_model - H_measured) / |H_measured| at every frequency (real and
imaginary parts), so every frequency counts alike whatever the FRF's magnitude; the parameters are
fitted as logarithms (positive by construction) with scipy.optimize.least_squares from several
starts, and `std` is each parameter's standard deviation from the fit's covariance
(s^2 (J^T J)^-1, s^2 the residual variance per degree of freedom).

A parameter the FRF cannot see (a damper in parallel with nothing that moves, a spring far too
stiff to flex) has no standard deviation worth the name: the Jacobian's column for it vanishes and
the pseudo-inverse gives it a tiny, meaningless one. `identifiable` marks those, from the
Jacobian's singular values (a parameter lying in the directions the FRF does not constrain) or a
relative standard deviation above 100 %.
"""
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import yaml
from scipy.optimize import least_squares

__all__ = ["ChainFit", "chain_receptance", "fit_chain", "read_frf_csv", "scene_snippet", "MAX_FREQUENCIES"]

# A laboratory FRF has tens to hundreds of frequencies; the fit's cost grows with their number
# (the least squares evaluate the chain at every one, some thousands of times from 9 starts), and
# 20,000 take minutes where 240,000 took hours. More is refused with a word, not left to run.
MAX_FREQUENCIES = 20000

MAX_FREQUENCY_HZ = 1e4

# A direction of the log-parameters whose singular value is below this share of the largest
# changes the FRF by less than the double's rounding of the residual can tell: not identified.
SINGULAR_RTOL = 1e-7


def chain_receptance(freq_hz, masses, stiffness, damping):
    """Head receptance X/F (m/N, complex) of a chain at the given frequencies (Hz)."""
    m, k, c = (np.asarray(v, float) for v in (masses, stiffness, damping))
    n = len(m)
    w = 2.0 * np.pi * np.asarray(freq_hz, float)
    # One dynamic stiffness matrix per frequency, solved together (numpy's batched solve).
    a = np.zeros((len(w), n, n), complex)
    for i in range(n):
        z = k[i] + 1j * w * c[i]
        a[:, i, i] += z - w * w * m[i]
        if i + 1 < n:  # spring i joins mass i to mass i + 1; the last one to the roof
            a[:, i + 1, i + 1] += z
            a[:, i, i + 1] -= z
            a[:, i + 1, i] -= z
    e = np.zeros((len(w), n, 1), complex)
    e[:, 0, 0] = 1.0
    return np.linalg.solve(a, e)[:, 0, 0]


@dataclass
class ChainFit:
    masses: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    std: dict             # name -> array of standard deviations, like the parameters
    residual_rms: float   # rms of the relative complex residual per frequency
    residual: np.ndarray  # complex relative residual per frequency
    # name -> array of bool: False where the FRF does not determine the parameter (see above)
    identifiable: dict = field(default_factory=dict)


def _split(p, n):
    v = np.exp(np.clip(p, -60.0, 60.0))  # a damper fitted to nothing goes to ~0, not to overflow
    return v[:n], v[n:2 * n], v[2 * n:]


def _starts(freq_hz, h, n):
    """Deterministic starting points: the head mass from the high-frequency apparent mass, the
    static stiffness from the low-frequency receptance, spread over the chain in a few ways."""
    am_hi = abs(-1.0 / ((2 * np.pi * freq_hz[-1]) ** 2 * h[-1]))
    k_static = 1.0 / max(abs(h[0]), 1e-12)
    starts = []
    for mass_ratio in (1.0, 2.0, 0.5):
        for k_ratio in (30.0, 100.0, 10.0):
            m = am_hi * mass_ratio ** np.arange(n)
            m[0] = am_hi
            k = k_static * n * k_ratio ** (n - 1 - np.arange(n))  # stiffer at the top, soft roof spring
            c = 2 * 0.2 * np.sqrt(k * m)
            starts.append(np.log(np.concatenate([m, k, c])))
    return starts


def fit_chain(freq_hz, receptance, masses=2):
    """Fits a chain of `masses` (2 or 3) to the receptance; returns a ChainFit."""
    if masses not in (2, 3):
        raise ValueError(f"masses = {masses!r}: allowed 2 or 3 (a two- or three-mass chain)")
    f = np.asarray(freq_hz, float)
    h = np.asarray(receptance, complex)
    if f.ndim != 1 or len(f) != len(h) or len(f) < 3 * masses + 1:
        raise ValueError(f"the FRF has {len(f)} frequencies: allowed at least {3 * masses + 1} "
                         f"(more than the {3 * masses} parameters)")
    if len(f) > MAX_FREQUENCIES:
        raise ValueError(f"the FRF has {len(f)} frequencies: allowed at most {MAX_FREQUENCIES} "
                         "(thin it, or fit a band with --fmin/--fmax)")
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(h)) and np.all(f > 0) and np.all(np.abs(h) > 0)):
        raise ValueError("the FRF has non-finite, zero or negative values: allowed frequencies > 0 Hz, "
                         "finite non-zero receptances")
    # Repeated rows at one frequency fix only that frequency's complex value: two equations, not
    # as many as rows. 3 n parameters need 3 n + 1 distinct frequencies, as for the count above.
    distinct = len(np.unique(f))
    if distinct < 3 * masses + 1:
        raise ValueError(f"the FRF has {distinct} distinct frequenc{'y' if distinct == 1 else 'ies'} "
                         f"({len(f)} rows): allowed at least {3 * masses + 1} distinct frequencies for the "
                         f"{3 * masses} parameters of a {masses}-mass chain")
    order = np.argsort(f)
    f, h = f[order], h[order]
    scale = np.abs(h)

    def residual(p):
        r = (chain_receptance(f, *_split(p, masses)) - h) / scale
        return np.concatenate([r.real, r.imag])

    best = None
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # a failed start is skipped below
        starts = _starts(f, h, masses)
    for p0 in starts:
        if not np.all(np.isfinite(p0)):
            continue
        try:
            sol = least_squares(residual, p0, method="lm", x_scale=1.0, max_nfev=4000)
        except (np.linalg.LinAlgError, ValueError):
            continue
        if best is None or sol.cost < best.cost:
            best = sol
    if best is None:
        raise RuntimeError("fit_chain: no start converged")
    m, k, c = _split(best.x, masses)
    r = residual(best.x)
    dof = max(1, len(r) - len(best.x))
    s2 = float(r @ r) / dof
    cov_log = s2 * np.linalg.pinv(best.jac.T @ best.jac)
    rel = np.sqrt(np.clip(np.diag(cov_log), 0, None))  # log-parameters: relative std
    values = np.exp(np.clip(best.x, -60.0, 60.0))
    std = values * rel
    # Directions of the log-parameters the FRF does not constrain: singular values of J far below
    # the largest. A parameter with most of its weight there is not identified, whatever the
    # pseudo-inverse says of its spread; nor is one known only to more than 100 %.
    _, sv, vt = np.linalg.svd(best.jac, full_matrices=True)
    sv = np.concatenate([sv, np.zeros(vt.shape[0] - len(sv))])
    blind = sv < SINGULAR_RTOL * max(sv.max(), np.finfo(float).tiny)
    weight_blind = np.sum(vt[blind] ** 2, axis=0)
    seen = (weight_blind < 0.5) & (rel <= 1.0)
    rc = r[:len(f)] + 1j * r[len(f):]
    split = {"masses": slice(0, masses), "stiffness": slice(masses, 2 * masses), "damping": slice(2 * masses, None)}
    return ChainFit(m, k, c, {name: std[sl] for name, sl in split.items()},
                    float(np.sqrt(np.mean(np.abs(rc) ** 2))), rc, {name: seen[sl] for name, sl in split.items()})


def read_frf_csv(path, columns="measured"):
    """(frequency_hz, receptance) from a CSV: pantograph_frf's frf.csv (columns "measured" or
    "analytic"), or any CSV with frequency_hz, receptance_re_m_per_n, receptance_im_m_per_n."""
    import io
    import os
    if os.path.isdir(path):
        raise ValueError(f"{path}: is a directory; expected an FRF CSV file")
    # Bounded before parsing: a file of millions of rows is refused, not read whole (a row of
    # frf.csv is about 200 bytes).
    if os.path.getsize(path) > 400 * MAX_FREQUENCIES:
        raise ValueError(f"{path}: {os.path.getsize(path)} bytes: allowed at most {400 * MAX_FREQUENCIES} "
                         f"(an FRF of at most {MAX_FREQUENCIES} frequencies; thin it, or cut a band out of it)")
    with open(path, "rb") as fh:
        raw = fh.read()
    if b"\0" in raw:
        line = raw[:raw.index(b"\0")].count(b"\n") + 1
        raise ValueError(f"{path}: not a text CSV file (a NUL byte on line {line})")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not a text CSV file ({e.reason} at byte {e.start})") from None
    try:
        d = pd.read_csv(io.StringIO(text), comment="#", nrows=MAX_FREQUENCIES + 1, dtype=str, keep_default_na=False,
                        skip_blank_lines=True)
    except pd.errors.EmptyDataError:
        raise ValueError(f"{path}: empty; expected a header line (frequency_hz, ...) and rows") from None
    except pd.errors.ParserError as e:
        raise ValueError(f"{path}: not a CSV table: {str(e).strip()}") from None
    if len(d) == 0:
        raise ValueError(f"{path}: no data rows under its header; expected one row per frequency")
    if len(d) > MAX_FREQUENCIES:
        raise ValueError(f"{path}: more than {MAX_FREQUENCIES} rows: allowed at most {MAX_FREQUENCIES} frequencies "
                         "(thin the FRF, or cut a band out of it)")
    for prefix in (f"{columns}_", ""):
        re_, im_ = f"{prefix}receptance_re_m_per_n", f"{prefix}receptance_im_m_per_n"
        if "frequency_hz" in d and re_ in d and im_ in d:
            cols = []
            for name in ("frequency_hz", re_, im_):
                vals = pd.to_numeric(d[name].str.strip(), errors="coerce").to_numpy(float)
                # Frequencies of a pantograph's FRF: above 0 and at most 10 kHz (laboratories stop
                # at 20-200 Hz); a receptance is a finite number.
                ok = (vals > 0) & (vals <= MAX_FREQUENCY_HZ) if name == "frequency_hz" else np.isfinite(vals)
                bad = np.flatnonzero(~ok)
                if bad.size:
                    i = int(bad[0])
                    allowed = (f"a frequency > 0 and <= {MAX_FREQUENCY_HZ:g} Hz" if name == "frequency_hz"
                               else "a finite number")
                    raise ValueError(f"{path}: data row {i + 1} (after the header), column {name}: "
                                     f"{d[name].iloc[i]!r}: allowed {allowed} ({bad.size} such row"
                                     f"{'' if bad.size == 1 else 's'})")
                cols.append(vals)
            return cols[0], cols[1] + 1j * cols[2]
    raise ValueError(f"{path}: needs the columns frequency_hz, {columns}_receptance_re_m_per_n and "
                     f"{columns}_receptance_im_m_per_n (pantograph_frf) or receptance_re_m_per_n and "
                     f"receptance_im_m_per_n; found {', '.join(d.columns)}")


def scene_snippet(fit, name="fitted", static_uplift=100.0, heads=0, head_spacing=0.5):
    """A `pantographs:` entry of a scene (docs/scene_reference.md) with the fitted chain; with
    heads = N >= 1, the chain's top mass written as N identical heads on their own suspensions to
    the frame (the rest of the chain), head_spacing metres apart along the track.

    The heads of a laboratory FRF are driven together: N identical heads (mass m, spring k, damper
    c to the frame) move as one mass N m on N k and N c, so the FRF fixes only those sums, and the
    fitted top mass, spring and damper are shared out equally. Unequal heads cannot be told apart
    from equal ones by such an FRF."""
    def numbers(v):
        # six significant digits, as plain floats (a YAML library writes them, not text pasting)
        return [float(f"{x:.6g}") for x in v]
    if heads:
        if isinstance(heads, bool) or not isinstance(heads, int) or heads < 1 or len(fit.masses) < 2:
            raise ValueError(f"heads = {heads!r}: allowed a whole number >= 1 on a chain of 2 or 3 masses "
                             "(the top one is shared out over the heads, the rest is the frame)")
    if not isinstance(name, str) or not name:
        raise ValueError(f"name = {name!r}: allowed a non-empty text")
    head = [f"fitted to a head FRF by fit_pantograph: rms relative residual {fit.residual_rms:.3g}",
            "static_uplift is not in an FRF: set it to the pantograph's static contact force"]
    blind = [f"{part}[{i}]" for part in ("masses", "stiffness", "damping")
             for i, ok in enumerate(fit.identifiable.get(part, [])) if not ok]
    if blind:
        head.append("not identifiable from this FRF (kept as fitted, check them): " + ", ".join(blind))
    entry = {"name": name, "type": "lumped"}
    if heads:
        n = heads
        head += [f"{n} identical heads: the FRF fixes their sums (N m, N k, N c), shared out equally",
                 "the heads' offsets are not in it either: set them to the pantograph's geometry",
                 "masses: the frame, top mass first, kg; stiffness below each frame mass, the last to the "
                 "roof, N/m; damping N s/m"]
        entry.update(masses=numbers(fit.masses[1:]), stiffness=numbers(fit.stiffness[1:]),
                     damping=numbers(fit.damping[1:]), static_uplift=float(f"{static_uplift:.6g}"))
        entry["heads"] = [{"mass": float(f"{fit.masses[0] / n:.6g}"), "stiffness": float(f"{fit.stiffness[0] / n:.6g}"),
                           "damping": float(f"{fit.damping[0] / n:.6g}"),
                           "offset": float(f"{(i - 0.5 * (n - 1)) * head_spacing:.6g}"), "collectors": [{"offset": 0.0}]}
                          for i in range(n)]
    else:
        head.append("masses head first, kg; stiffness below each mass, the last to the roof, N/m; damping N s/m")
        entry.update(masses=numbers(fit.masses), stiffness=numbers(fit.stiffness), damping=numbers(fit.damping),
                     static_uplift=float(f"{static_uplift:.6g}"))
    body = yaml.safe_dump({"pantographs": [entry]}, sort_keys=False, default_flow_style=None, allow_unicode=True,
                          width=1 << 16)
    return "".join("# " + line.replace("\n", " ") + "\n" for line in head) + body
