"""Plots of a study's results table (matplotlib, Agg): maps for grids, histograms and scatter for
random studies, Sobol indices with their intervals. Draws only; computes no physics."""
import json
import os

import numpy as np


def _save(fig, path):
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)


def plot_study(study, table, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = [p["key"] for p in study["parameters"]]
    ok = table[table["status"] == "ok"]
    written = []
    for o in study["outputs"]:
        safe = o.replace(".", "_")
        if study["sampling"] == "grid" and len(keys) == 2:
            piv = ok.pivot_table(index=keys[1], columns=keys[0], values=o)
            fig, ax = plt.subplots(figsize=(7, 5))
            im = ax.pcolormesh(np.arange(piv.shape[1] + 1), np.arange(piv.shape[0] + 1), piv.to_numpy(), shading="flat")
            ax.set_xticks(np.arange(piv.shape[1]) + 0.5, [f"{v:g}" for v in piv.columns])
            ax.set_yticks(np.arange(piv.shape[0]) + 0.5, [f"{v:g}" for v in piv.index])
            vals = piv.to_numpy()
            mid = np.nanmin(vals) + 0.6 * (np.nanmax(vals) - np.nanmin(vals))
            for (r, c), v in np.ndenumerate(vals):  # dark text on the light end of viridis
                ax.text(c + 0.5, r + 0.5, f"{v:.3g}", ha="center", va="center", fontsize=9,
                        color="k" if v > mid else "w")
            ax.set_xlabel(keys[0])
            ax.set_ylabel(keys[1])
            fig.colorbar(im, ax=ax, label=o)
            ax.set_title(f"{study['name']}: {o}")
        elif study["sampling"] == "grid" and len(keys) == 1:
            fig, ax = plt.subplots(figsize=(7, 4.5))
            ax.plot(ok[keys[0]], ok[o], "o-")
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
        fig.tight_layout()
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
