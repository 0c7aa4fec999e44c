"""Plots of a study's results table (matplotlib, Agg): maps for grids, histograms and scatter for
random studies, Sobol indices with their intervals. Draws only; computes no physics."""
import json
import os

import numpy as np


def _save(fig, path):
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)


def _tick(v):
    return f"{v:g}" if isinstance(v, (int, float, np.integer, np.floating)) else str(v)


def _find(labels, v):
    """Where a table's value is among a grid's labels (a label 80 may come back as 80.0)."""
    for j, x in enumerate(labels):
        if str(x) == str(v):
            return j
    for j, x in enumerate(labels):
        try:
            if float(x) == float(v):
                return j
        except (TypeError, ValueError):
            pass
    raise ValueError(f"{v!r} is not among the grid's labels")


def plot_study(study, table, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    keys = [p["key"] for p in study["parameters"]]
    ok = table[table["status"] == "ok"]
    written = []
    for o in study["outputs"]:
        safe = o.replace(".", "_")
        if study["sampling"] == "grid" and len(keys) in (2, 3):
            # A map of the first two parameters; with a third, one map per value of it, on one
            # colour scale so that the maps compare.
            params = study["parameters"]
            panels = params[2]["labels"] if len(keys) == 3 else [None]
            vals_all = ok[o].to_numpy(dtype=float)
            finite = vals_all[np.isfinite(vals_all)]
            vmin, vmax = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
            cols = min(len(panels), 3)
            rows = (len(panels) + cols - 1) // cols
            fig, axes = plt.subplots(rows, cols, figsize=(5.4 * cols + 1.2, 4.4 * rows + 0.4), squeeze=False,
                                     layout="constrained")
            for ax in axes.flat[len(panels):]:
                ax.set_visible(False)
            # Every grid value has its row and column, in grid order (labels may be text), whether
            # or not any of its cases ran: a value whose cases all failed is a column of failed
            # cells, not a column left out.
            xs, ys = params[0]["labels"], params[1]["labels"]
            any_failed = False
            for n, (ax, panel) in enumerate(zip(axes.flat, panels)):
                sub = table if panel is None else table[table[keys[2]].astype(str) == str(panel)]
                vals = np.full((len(ys), len(xs)), np.nan)
                failed = np.zeros(vals.shape, bool)
                for _, row in sub.iterrows():
                    r, c = _find(ys, row[keys[1]]), _find(xs, row[keys[0]])
                    if row["status"] == "ok":
                        vals[r, c] = float(row[o])
                    else:
                        failed[r, c] = True
                im = ax.pcolormesh(np.arange(len(xs) + 1), np.arange(len(ys) + 1), vals, shading="flat",
                                   vmin=vmin, vmax=vmax)
                for r, c in zip(*np.nonzero(failed)):  # hatched: a case that failed (message in results.csv)
                    ax.add_patch(Rectangle((c, r), 1, 1, facecolor="0.92", edgecolor="0.45", hatch="xx", lw=0.0))
                    any_failed = True
                ax.set_xlim(0, len(xs))
                ax.set_ylim(0, len(ys))
                ax.set_xticks(np.arange(len(xs)) + 0.5, [_tick(v) for v in params[0]["labels"]],
                              rotation=30 if any(len(_tick(v)) > 6 for v in params[0]["labels"]) else 0, ha="right"
                              if any(len(_tick(v)) > 6 for v in params[0]["labels"]) else "center", fontsize=8)
                ax.set_yticks(np.arange(len(ys)) + 0.5, [_tick(v) for v in params[1]["labels"]], fontsize=8)
                mid = vmin + 0.6 * (vmax - vmin)
                for (r, c), v in np.ndenumerate(vals):  # dark text on the light end of viridis
                    if np.isfinite(v):
                        ax.text(c + 0.5, r + 0.5, f"{v:.3g}", ha="center", va="center", fontsize=8,
                                color="k" if v > mid else "w")
                    elif failed[r, c]:
                        ax.text(c + 0.5, r + 0.5, "failed", ha="center", va="center", fontsize=7, color="k",
                                bbox=dict(boxstyle="square,pad=0.1", fc="0.92", ec="none"))
                    else:  # no case (a grid cell without a row): left blank, said in its cell
                        ax.text(c + 0.5, r + 0.5, "no case", ha="center", va="center", fontsize=7, color="0.5")
                ax.set_xlabel(keys[0])
                if n % cols == 0:  # the rows share the y axis: one label, at the left
                    ax.set_ylabel(keys[1])
                ax.set_title(f"{keys[2]} = {_tick(panel)}" if panel is not None else f"{study['name']}: {o}",
                             fontsize=10)
            fig.colorbar(im, ax=axes.ravel().tolist(), label=o)
            if any_failed:  # below the first map (constrained layout makes room for it)
                axes.flat[0].legend(handles=[Rectangle((0, 0), 1, 1, facecolor="0.92", edgecolor="0.45", hatch="xx",
                                                       label="case failed (message in results.csv)")],
                                    loc="upper left", bbox_to_anchor=(0.0, -0.2), fontsize=8, frameon=False)
            if len(keys) == 3:
                fig.suptitle(f"{study['name']}: {o}")
        elif study["sampling"] == "grid" and len(keys) == 1:
            fig, ax = plt.subplots(figsize=(7, 4.5))
            bad = table[table["status"] != "ok"]
            if all(isinstance(x, (int, float)) for x in study["parameters"][0]["labels"]):
                ax.plot(ok[keys[0]], ok[o], "o-")
                bad_x = bad[keys[0]].astype(float)
            else:  # named values: in grid order, one tick each
                order = {str(x): j for j, x in enumerate(study["parameters"][0]["labels"])}
                xs = [order[str(x)] for x in ok[keys[0]]]
                ax.plot(xs, ok[o], "o")
                ax.set_xticks(range(len(order)), list(order), rotation=30, ha="right", fontsize=8)
                bad_x = [order[str(x)] for x in bad[keys[0]]]
            if len(bad):  # a value whose case failed: marked on the axis, not left out
                ax.plot(bad_x, np.zeros(len(bad)), "x", color="tab:red", ms=9, mew=2, clip_on=False,
                        transform=ax.get_xaxis_transform(), label="case failed (message in results.csv)")
                ax.legend(fontsize=8)
            ax.set_xlabel(keys[0])
            ax.set_ylabel(o)
            ax.grid(True, alpha=0.3)
            ax.set_title(f"{study['name']}: {o}")
        else:
            # Seeds of random lines (integer draws) carry no order worth a scatter plot.
            keys_x = [p["key"] for p in study["parameters"]
                      if p.get("distribution", {}).get("type") != "integers"]
            n = len(keys_x)
            fig, axes = plt.subplots(1, n + 1, figsize=(max(6.5, 4 * (n + 1)), 3.8), squeeze=False)
            axes = axes[0]
            axes[0].hist(ok[o].dropna(), bins=min(40, max(5, len(ok) // 5)), color="tab:blue", alpha=0.8)
            axes[0].set_xlabel(o)
            axes[0].set_ylabel("cases")
            axes[0].set_title(f"{len(ok)} cases")
            for ax, k in zip(axes[1:], keys_x):
                ax.scatter(ok[k], ok[o], s=8, alpha=0.6)
                ax.set_xlabel(k)
                ax.set_ylabel(o)
                ax.grid(True, alpha=0.3)
            fig.suptitle(f"{study['name']}: {o}")
        if not (study["sampling"] == "grid" and len(keys) in (2, 3)):
            fig.tight_layout()  # (the maps share a colour bar placed by matplotlib itself)
        path = os.path.join(out, f"{safe}.png")
        _save(fig, path)
        plt.close(fig)
        written.append(path)
    sens_path = os.path.join(out, "sensitivity.json")
    if study["sampling"] == "saltelli" and os.path.exists(sens_path):
        with open(sens_path) as f:
            sens = json.load(f)
        for o, r in sens["outputs"].items():
            if "S1" not in r:
                continue
            fig, ax = plt.subplots(figsize=(1.6 * len(keys) + 3, 4))
            x = np.arange(len(keys))
            for off, name, color in ((-0.18, "S1", "tab:blue"), (0.18, "ST", "tab:orange")):
                v = np.array(r[name], float)
                err = None
                if name + "_conf" in r:
                    lo, hi = np.array(r[name + "_conf"][0]), np.array(r[name + "_conf"][1])
                    err = np.vstack([np.clip(v - lo, 0, None), np.clip(hi - v, 0, None)])
                ax.bar(x + off, v, 0.36, yerr=err, capsize=3, color=color,
                       label={"S1": "first order", "ST": "total"}[name])
            ax.set_xticks(x, [k.replace(".", ".\n", 1) for k in keys], fontsize=8)
            ax.set_ylabel("Sobol index")
            ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]))
            ax.legend()
            ax.grid(True, axis="y", alpha=0.3)
            ax.set_title(f"sensitivity of {o} ({sens['samples']} x {len(keys) + 2} passes)")
            fig.tight_layout()
            path = os.path.join(out, f"sobol_{o.replace('.', '_')}.png")
            _save(fig, path)
            plt.close(fig)
            written.append(path)
    return written
