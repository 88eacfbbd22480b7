#!/usr/bin/python3
"""Plots of make select-eval: one PNG per scene CSV written by occ_select_eval, quality (share of scene
rays whose predicted depth lies within 2 sigma of the scene's) against points acquired, one panel per
budget, one curve per strategy, with (a)'s full frames as markers and each guided run's stop point.

Usage: /usr/bin/python3 scripts/plot_select.py OUT_DIR   (reads OUT_DIR/*.csv except summary.csv)
"""
import csv
import glob
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt

STYLE = {
    "b_uniform": ("(b) uniform random", "tab:gray", "-"),
    "c_decimation": ("(c) decimation", "tab:brown", ":"),
    "d_guided": ("(d) improvement", "tab:blue", "-"),
    "e_returns": ("(e) + return model", "tab:orange", "-"),
    "f_reacquire": ("(f) + re-acquisition", "tab:green", "--"),
}


def read_runs(path):
    runs = {}
    for row in csv.DictReader(open(path)):
        key = (row["strategy"], int(row["budget_rays"]))
        runs.setdefault(key, []).append(row)
    return runs


def plot_scene(path):
    runs = read_runs(path)
    scene = os.path.splitext(os.path.basename(path))[0]
    full = next(rows for (s, _), rows in runs.items() if s == "a_full")
    frame_rays = int(full[0]["budget_rays"])
    budgets = sorted({b for (s, b) in runs if s != "a_full"})
    fig, axes = plt.subplots(1, len(budgets), figsize=(5 * len(budgets), 4), sharey=True, squeeze=False)
    target = 0.95 * float(full[-1]["quality"])
    for ax, budget in zip(axes[0], budgets):
        ax.plot([int(r["rays_asked"]) / frame_rays for r in full], [float(r["quality"]) for r in full], "ks",
                label="(a) full frames")
        for strategy, (label, colour, line) in STYLE.items():
            rows = runs.get((strategy, budget))
            if not rows:
                continue
            x = [int(r["rays_asked"]) / frame_rays for r in rows]
            ax.plot(x, [float(r["quality"]) for r in rows], line, color=colour, label=label)
            stops = [i for i, r in enumerate(rows) if r["plan_stop"] == "1"]
            if stops and strategy != "d_guided":
                ax.plot(x[stops[0]], float(rows[stops[0]]["quality"]), "v", color=colour, markersize=8)
        ax.axhline(target, color="k", linewidth=0.5, linestyle="--")
        ax.set_title(f"{scene}: {budget} rays per shot ({100 * budget / frame_rays:.0f}%)")
        ax.set_xlabel("points acquired (full frames)")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("share of rays within 2 sigma of the scene")
    axes[0][0].legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    out = os.path.join(os.path.dirname(path), scene + ".png")
    fig.savefig(out, dpi=80)
    plt.close(fig)
    return out


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    paths = [p for p in sorted(glob.glob(os.path.join(sys.argv[1], "*.csv"))) if not p.endswith("summary.csv")]
    if not paths:
        sys.exit(f"plot_select: no scene CSV in {sys.argv[1]}")
    for p in paths:
        print("wrote", plot_scene(p))


if __name__ == "__main__":
    main()
