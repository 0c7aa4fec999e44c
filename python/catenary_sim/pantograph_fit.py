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
"""
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

__all__ = ["ChainFit", "chain_receptance", "fit_chain", "read_frf_csv", "scene_snippet"]


def chain_receptance(freq_hz, masses, stiffness, damping):
    """Head receptance X/F (m/N, complex) of a chain at the given frequencies (Hz)."""
    m, k, c = (np.asarray(v, float) for v in (masses, stiffness, damping))
    n = len(m)
    out = np.empty(len(freq_hz), complex)
    for j, f in enumerate(np.asarray(freq_hz, float)):
        w = 2.0 * np.pi * f
        a = np.zeros((n, n), complex)
        for i in range(n):
            z = k[i] + 1j * w * c[i]
            a[i, i] += z - w * w * m[i]
            if i + 1 < n:  # spring i joins mass i to mass i + 1; the last one to the roof
                a[i + 1, i + 1] += z
                a[i, i + 1] -= z
                a[i + 1, i] -= z
        e = np.zeros(n)
        e[0] = 1.0
        out[j] = np.linalg.solve(a, e)[0]
    return out


@dataclass
class ChainFit:
    masses: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    std: dict             # name -> array of standard deviations, like the parameters
    residual_rms: float   # rms of the relative complex residual per frequency
    residual: np.ndarray  # complex relative residual per frequency


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
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(h)) and np.all(f > 0) and np.all(np.abs(h) > 0)):
        raise ValueError("the FRF has non-finite, zero or negative values: allowed frequencies > 0 Hz, "
                         "finite non-zero receptances")
    order = np.argsort(f)
    f, h = f[order], h[order]
    scale = np.abs(h)

    def residual(p):
        r = (chain_receptance(f, *_split(p, masses)) - h) / scale
        return np.concatenate([r.real, r.imag])

    best = None
    for p0 in _starts(f, h, masses):
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
    rc = r[:len(f)] + 1j * r[len(f):]
    return ChainFit(m, k, c, {"masses": std[:masses], "stiffness": std[masses:2 * masses], "damping": std[2 * masses:]},
                    float(np.sqrt(np.mean(np.abs(rc) ** 2))), rc)


def read_frf_csv(path, columns="measured"):
    """(frequency_hz, receptance) from a CSV: pantograph_frf's frf.csv (columns "measured" or
    "analytic"), or any CSV with frequency_hz, receptance_re_m_per_n, receptance_im_m_per_n."""
    d = pd.read_csv(path, comment="#")
    for prefix in (f"{columns}_", ""):
        re_, im_ = f"{prefix}receptance_re_m_per_n", f"{prefix}receptance_im_m_per_n"
        if "frequency_hz" in d and re_ in d and im_ in d:
            return d["frequency_hz"].to_numpy(float), d[re_].to_numpy(float) + 1j * d[im_].to_numpy(float)
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
    def fmt(v):
        return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"
    if heads:
        if not isinstance(heads, int) or heads < 1 or len(fit.masses) < 2:
            raise ValueError(f"heads = {heads!r}: allowed a whole number >= 1 on a chain of 2 or 3 masses "
                             "(the top one is shared out over the heads, the rest is the frame)")
        n = heads
        lines = [f"# fitted to a head FRF by fit_pantograph: rms relative residual {fit.residual_rms:.3g}",
                 f"# {n} identical heads: the FRF fixes their sums (N m, N k, N c), shared out equally",
                 "# static_uplift is not in an FRF: set it to the pantograph's static contact force;",
                 "# the heads' offsets are not in it either: set them to the pantograph's geometry",
                 "pantographs:", f"  - name: {name}", "    type: lumped",
                 f"    masses: {fmt(fit.masses[1:])}        # kg, the frame, top mass first",
                 f"    stiffness: {fmt(fit.stiffness[1:])}  # N/m, below each frame mass, the last to the roof",
                 f"    damping: {fmt(fit.damping[1:])}      # N s/m",
                 f"    static_uplift: {static_uplift:.6g}", "    heads:"]
        for i in range(n):
            off = (i - 0.5 * (n - 1)) * head_spacing
            lines.append(f"      - {{mass: {fit.masses[0] / n:.6g}, stiffness: {fit.stiffness[0] / n:.6g}, "
                         f"damping: {fit.damping[0] / n:.6g}, offset: {off:.6g}, collectors: [{{offset: 0.0}}]}}")
        return "\n".join(lines) + "\n"
    return (f"# fitted to a head FRF by fit_pantograph: rms relative residual {fit.residual_rms:.3g}\n"
            f"# static_uplift is not in an FRF: set it to the pantograph's static contact force\n"
            f"pantographs:\n"
            f"  - name: {name}\n"
            f"    type: lumped\n"
            f"    masses: {fmt(fit.masses)}        # kg, head first\n"
            f"    stiffness: {fmt(fit.stiffness)}  # N/m, below each mass, the last to the roof\n"
            f"    damping: {fmt(fit.damping)}      # N s/m\n"
            f"    static_uplift: {static_uplift:.6g}\n")
