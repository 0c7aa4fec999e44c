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


def plot_study(study, table, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

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
            for n, (ax, panel) in enumerate(zip(axes.flat, panels)):
                sub = ok if panel is None else ok[ok[keys[2]].astype(str) == str(panel)]
                piv = sub.pivot_table(index=keys[1], columns=keys[0], values=o, dropna=False)
                # grid order, not sorted order (labels may be text)
                piv = piv.reindex(index=[x for x in params[1]["labels"] if x in piv.index],
                                  columns=[x for x in params[0]["labels"] if x in piv.columns])
                vals = piv.to_numpy(dtype=float)
                im = ax.pcolormesh(np.arange(piv.shape[1] + 1), np.arange(piv.shape[0] + 1), vals, shading="flat",
                                   vmin=vmin, vmax=vmax)
                ax.set_xticks(np.arange(piv.shape[1]) + 0.5, [_tick(v) for v in piv.columns],
                              rotation=30 if any(len(_tick(v)) > 6 for v in piv.columns) else 0, ha="right"
                              if any(len(_tick(v)) > 6 for v in piv.columns) else "center", fontsize=8)
                ax.set_yticks(np.arange(piv.shape[0]) + 0.5, [_tick(v) for v in piv.index], fontsize=8)
                mid = vmin + 0.6 * (vmax - vmin)
                for (r, c), v in np.ndenumerate(vals):  # dark text on the light end of viridis
                    if np.isfinite(v):
                        ax.text(c + 0.5, r + 0.5, f"{v:.3g}", ha="center", va="center", fontsize=8,
                                color="k" if v > mid else "w")
                    else:  # a case that failed (its message is in results.csv)
                        ax.text(c + 0.5, r + 0.5, "failed", ha="center", va="center", fontsize=7, color="0.5")
                ax.set_xlabel(keys[0])
                if n % cols == 0:  # the rows share the y axis: one label, at the left
                    ax.set_ylabel(keys[1])
                ax.set_title(f"{keys[2]} = {_tick(panel)}" if panel is not None else f"{study['name']}: {o}",
                             fontsize=10)
            fig.colorbar(im, ax=axes.ravel().tolist(), label=o)
            if len(keys) == 3:
                fig.suptitle(f"{study['name']}: {o}")
        elif study["sampling"] == "grid" and len(keys) == 1:
            fig, ax = plt.subplots(figsize=(7, 4.5))
            if all(isinstance(x, (int, float)) for x in study["parameters"][0]["labels"]):
                ax.plot(ok[keys[0]], ok[o], "o-")
            else:  # named values: in grid order, one tick each
                order = {str(x): j for j, x in enumerate(study["parameters"][0]["labels"])}
                xs = [order[str(x)] for x in ok[keys[0]]]
                ax.plot(xs, ok[o], "o")
                ax.set_xticks(range(len(order)), list(order), rotation=30, ha="right", fontsize=8)
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
