"""The page of a comparison (catenary_sim.measurement.Comparison.write): report.html with every
picture embedded, and the same pictures as report_*.png. It draws what the comparison computed
and computes nothing itself; the page's layout follows scripts/pass_report's."""
import base64
import html
import io
import math

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

RECORD, SIMULATED = "tab:red", "tab:blue"
LABELS = {"mean_force_N": "mean force Fm (N)", "std_force_N": "standard deviation (N)",
          "stat_max_force_N": "statistical max Fm + 3 std (N)", "stat_min_force_N": "statistical min Fm - 3 std (N)",
          "max_force_N": "actual max (N)", "min_force_N": "actual min (N)",
          "contact_loss_percent": "contact loss (% of samples, filtered force <= 0)",
          "force_rms_difference_N": "rms of simulated - record (N)",
          "force_max_abs_difference_N": "largest |simulated - record| (N)",
          "spectrum_rms_difference_dB": "rms difference of the spectra up to the cutoff (dB)",
          "head_std_m": "head displacement std (m)", "head_range_m": "head displacement range (m)",
          "max_uplift_m": "largest uplift at the steady arm (m)"}


def _png(fig):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    return buf.getvalue()


def _marks(ax, c, lo, hi):
    for x in c.support_stations_m:
        if lo <= x <= hi:
            ax.axvline(x, color="0.6", lw=0.7, zorder=0)
    a0, a1 = c.settings["section_m"]
    ax.axvspan(a0, a1, color="tab:green", alpha=0.06, zorder=0)


def _fmt(v, unit):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if unit == "m":
        return "%.2f mm" % (1e3 * v)
    return "%.2f" % v if abs(v) < 1e4 else "%.4g" % v


def pictures(c):
    s = c.series
    x = s["station_m"].to_numpy()
    lo, hi = float(x.min()), float(x.max())
    names = list(c.record.force_N)
    out = []
    fig, axes = plt.subplots(2 * len(names), 1, figsize=(11, 5.6 * len(names)), squeeze=False, sharex=True,
                             gridspec_kw={"height_ratios": [3, 1] * len(names)})
    for i, p in enumerate(names):
        ax, dx = axes[2 * i][0], axes[2 * i + 1][0]
        ax.plot(x, s[f"record_force_{p}_N"], color="0.75", lw=0.6, label="record as measured")
        ax.plot(x, s[f"record_force_{p}_filtered_N"], color=RECORD, lw=1.2, label="record, filtered")
        ax.plot(x, s[f"simulated_force_{p}_filtered_N"], color=SIMULATED, lw=1.2, ls="--",
                label="simulated measuring pantograph, filtered")
        _marks(ax, c, lo, hi)
        # The range of the analysis section (the line's ends, where the pantograph meets the
        # anchors, can spike far above it), with room on top for the legend.
        inside = s["in_section"].to_numpy() > 0
        if inside.any():
            both = np.concatenate([s[f"record_force_{p}_N"].to_numpy()[inside],
                                   s[f"simulated_force_{p}_filtered_N"].to_numpy()[inside]])
            top, bottom = float(np.max(both)), min(0.0, float(np.min(both)))
            ax.set_ylim(bottom - 0.05 * (top - bottom), top + 0.35 * (top - bottom))
        ax.set_ylabel("contact force (N)")
        ax.set_title("%s: contact force against station (filtered at %g Hz; green: analysis section)" % (
            p, c.settings["cutoff_hz"]), fontsize=11)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right", ncol=3, framealpha=0.9)
        dx.plot(x, s[f"simulated_force_{p}_filtered_N"] - s[f"record_force_{p}_filtered_N"], color="k", lw=0.8)
        _marks(dx, c, lo, hi)
        dx.set_ylabel("simulated -\nrecord (N)")
        dx.grid(alpha=0.3)
    axes[-1][0].set_xlabel("station of %s (m, the record's stations)" % c.settings["station_of"])
    axes[-1][0].set_xlim(lo, hi)
    fig.tight_layout()
    out.append(("force", "Contact force against station", _png(fig),
                "The record and the simulated measuring pantograph, both low-pass filtered alike; below, their "
                "difference. Grey lines: supports."))

    fig, ax = plt.subplots(figsize=(11, 4.0))
    fmax = min(c.settings["cutoff_hz"], c.settings["record_bandwidth_hz"])
    for i, p in enumerate(names):
        t = c.spectra[c.spectra["pantograph"] == p]
        f = t["frequency_hz"].to_numpy()
        for col, color, lab in (("record_psd_N2_per_hz", RECORD, "record"),
                                ("simulated_psd_N2_per_hz", SIMULATED, "simulated")):
            v = t[col].to_numpy()
            ok = v > 0
            ax.semilogy(f[ok], v[ok], color=color, lw=1.0, ls="-" if lab == "record" else "--",
                        alpha=1.0 if i == 0 else 0.6, label="%s %s" % (p, lab))
    sp = c.settings["span_passing_hz"]  # None without a span (a line of fewer than two supports)
    harmonics = range(1, min(199, int(1.5 * fmax / sp)) + 1) if sp else ()  # (at most 199 lines)
    for h in harmonics:
        ax.axvline(h * sp, color="tab:green", lw=1.2 if h == 1 else 0.5, ls="-" if h == 1 else ":",
                   label="span passing %.2f Hz and harmonics" % sp if h == 1 else None)
    ax.axvline(fmax, color="k", lw=1.0, ls="-.", label="compared up to %g Hz" % fmax)
    top = float(np.max(c.spectra[["record_psd_N2_per_hz", "simulated_psd_N2_per_hz"]].to_numpy()))
    if top > 0:
        ax.set_ylim(top * 1e-7, top * 30)  # seven decades: what lies below is beyond the bandwidth
    ax.set_xlim(0, 1.5 * fmax)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("PSD of the contact force (N$^2$/Hz)")
    ax.set_title("Contact-force spectra over the analysis section (Welch, %.2f s segments)" %
                 c.settings["welch_segment_s"], fontsize=11)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    out.append(("spectrum", "Contact-force spectra", _png(fig),
                "Power spectral density of each side's force as measured (before the analysis filter)."))

    supports = list(c.record.support_station_m)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 3.8), gridspec_kw={"width_ratios": [1.6, 1]})
    if supports:
        for k, name in enumerate(supports):
            color = plt.cm.tab10(k % 10)
            ax.plot(x, 1e3 * s[f"record_uplift_{name}_m"], color=color, lw=1.0)
            ax.plot(x, 1e3 * s[f"simulated_uplift_{name}_m"], color=color, lw=1.0, ls="--")
        ax.plot([], [], color="k", label="record"), ax.plot([], [], color="k", ls="--", label="simulated")
        ax.legend(fontsize=8)
        rows = [r for r in c.rows if r["quantity"] == "max_uplift_m"]
        xs = np.arange(len(rows))
        bx.bar(xs - 0.2, [1e3 * (r["record"] or 0) for r in rows], 0.4, color=RECORD, label="record")
        bx.bar(xs + 0.2, [1e3 * (r["simulated"] or 0) for r in rows], 0.4, color=SIMULATED, label="simulated")
        bx.set_xticks(xs, [r["of"] for r in rows], fontsize=8)
        bx.legend(fontsize=8, loc="lower right")
    else:
        for a in (ax, bx):
            a.text(0.5, 0.5, "the record has no uplift column", ha="center", va="center", transform=a.transAxes)
    _marks(ax, c, lo, hi)
    ax.set_xlim(lo, hi)
    ax.set_xlabel("station of %s (m)" % c.settings["station_of"])
    ax.set_ylabel("steady-arm uplift (mm)")
    ax.set_title("Uplift of the recorded steady arms", fontsize=11)
    bx.set_ylabel("largest uplift (mm)")
    bx.set_title("Largest uplift while the pantograph passes", fontsize=11)
    ax.grid(alpha=0.3)
    bx.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    out.append(("uplift", "Uplift at the steady arms", _png(fig),
                "Each recorded steady arm's uplift and the simulated one, and their largest within half a span."))

    fig, ax = plt.subplots(figsize=(11, 3.0))
    if "record_speed_kmh" in s:
        ax.plot(x, s["record_speed_kmh"], color=RECORD, lw=1.0, label="record")
    ax.plot(x, s["profile_speed_kmh"], color="0.4", lw=1.0, ls=":", label="profile (%s)" % c.settings["speed_profile"])
    ax.plot(x, s["simulated_speed_kmh"], color=SIMULATED, lw=1.0, ls="--", label="simulated train")
    _marks(ax, c, lo, hi)
    ax.set_xlim(lo, hi)
    ax.set_xlabel("station (m)")
    ax.set_ylabel("speed (km/h)")
    ax.set_title("Speed: the profile that drove the simulated train", fontsize=11)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    out.append(("speed", "Speed profile", _png(fig), "The record's speed, the profile applied and the simulated "
                                                      "train's speed at the record's stations."))
    return out


def table(c):
    head = ("<tr><th>quantity</th><th>of</th><th>record</th><th>simulated</th><th>simulated - record</th>"
            "<th>relative</th><th>tolerance</th><th>mark</th></tr>")
    rows = []
    for r in c.rows:
        rel = "%+.2f %%" % (100 * r["relative_deviation"]) if r["relative_deviation"] is not None else ""
        dev = r["deviation"]
        if r["within"] is None:
            mark = "no tolerance given" if dev is not None else ""
        else:
            mark = '<span class="%s">%s</span>' % ("pass" if r["within"] else "fail",
                                                   "within" if r["within"] else "OUTSIDE")
        tol = r["tolerance"] or ""
        if tol and r["unit"] == "m":
            tol += " m"
        rows.append("<tr><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td>"
                    "</tr>" % (html.escape(LABELS.get(r["quantity"], r["quantity"])), html.escape(str(r["of"])),
                               _fmt(r["record"], r["unit"]), _fmt(r["simulated"], r["unit"]),
                               ("%+.4g" % (1e3 * dev) + " mm" if r["unit"] == "m" else "%+.4g" % dev)
                               if dev is not None else "-", rel, html.escape(tol), mark))
    return "<table>" + head + "".join(rows) + "</table>"


def build(c):
    """{file name: bytes} of the page and its pictures."""
    pics = pictures(c)
    st = c.settings
    within = c.within()
    verdict = ("no tolerance was given: the deviations are reported, not judged" if within is None else
               "every deviation is within its tolerance" if within else "some deviations are OUTSIDE their tolerance")
    title = "Record beside simulation: %s on %s" % (c.record.path, c.scene_name)
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>%s</title>" % html.escape(title),
             "<style>body{font-family:sans-serif;max-width:1120px;margin:1em auto;color:#222}"
             "table{border-collapse:collapse;font-size:14px}td,th{border:1px solid #bbb;padding:3px 8px;"
             "text-align:right}td:first-child,th:first-child{text-align:left}.pass{color:#070;font-weight:bold}"
             ".fail{color:#b00;font-weight:bold}img{max-width:100%;border:1px solid #ddd}"
             "figcaption{font-size:13px;color:#555;margin-bottom:1.5em}</style></head><body>",
             "<h1>%s</h1>" % html.escape(title),
             "<p>Both sides: the measuring pantograph's view at the record's bandwidth (%g Hz), sampled at the "
             "record's %g Hz rows, low-pass filtered at %g Hz (%s; 4th-order Butterworth, zero phase), statistics over "
             "the analysis section %.1f - %.1f m (%d rows). Speed: %s, mean %.1f km/h through the section. %s.</p>" % (
                 st["record_bandwidth_hz"], st["record_sample_rate_hz"], st["cutoff_hz"],
                 html.escape(st["cutoff_source"]), st["section_m"][0], st["section_m"][1], st["rows_in_section"],
                 html.escape(st["speed_profile"]), st["mean_speed_kmh"], verdict),
             "<h2 id='statistics'>Statistics</h2>", table(c)]
    for name, caption_title, png, caption in pics:
        parts.append("<h2 id='%s'>%s</h2>" % (name, html.escape(caption_title)))
        parts.append("<figure><img alt='%s' src='data:image/png;base64,%s'><figcaption>%s</figcaption></figure>" % (
            html.escape(caption_title), base64.b64encode(png).decode("ascii"), html.escape(caption)))
    parts.append("</body></html>\n")
    files = {"report_%s.png" % name: png for name, _t, png, _c in pics}
    files["report.html"] = "\n".join(parts).encode("utf-8")
    return files
