#!/usr/bin/python3
"""Plots and the table of make filter-eval, from the filter.csv occ_filter_eval writes.

- OUT_DIR/filter_<pct>pct.png per kept fraction: quality (share of the all-points map's surface columns
  whose predicted depth lies within 2 sigma(z)) against points kept so far, one curve per strategy;
- OUT_DIR/table.md: per fraction and strategy, the quality after frames 1, 10, 25 and 50 (or the last),
  the points kept, the largest deviation of a frame's kept count from the asked one, the distinct rays
  per kept point over the run (1: every kept point on its own ray), and VoxelGrid's leaf.

Usage: /usr/bin/python3 scripts/plot_filter.py OUT_DIR
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt

STYLE = {
    "improvement": ("ImprovementFilter (top fraction)", "tab:blue", "-"),
    "improvement_shuffled": ("ImprovementFilter, points shuffled", "tab:orange", "--"),
    "random_sample": ("pcl::RandomSample", "tab:gray", "-"),
    "voxel_grid": ("pcl::VoxelGrid (leaf bisected)", "tab:green", ":"),
}
CHECKPOINTS = (1, 10, 25, 50)


def read_runs(path):
    runs = {}
    for row in csv.DictReader(open(path)):
        runs.setdefault((float(row["fraction"]), row["strategy"]), []).append(row)
    return runs


def plot(runs, fraction, out_dir):
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for strategy, (label, colour, line) in STYLE.items():
        rows = runs.get((fraction, strategy))
        if not rows:
            continue
        ax.plot([int(r["points"]) / 1e6 for r in rows], [float(r["quality"]) for r in rows],
                line, color=colour, label=label)
    ax.set_xlabel("points kept so far [millions]")
    ax.set_ylabel("quality against the map from all points")
    ax.set_title(f"7-Scenes redkitchen, {len(rows)} posed frames, {fraction:.0%} of each frame kept")
    ax.set_ylim(0, 1)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    path = os.path.join(out_dir, f"filter_{round(fraction * 100)}pct.png")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def table(runs):
    lines = ["| fraction | strategy | " + " | ".join(f"quality after {f}" for f in CHECKPOINTS) +
             " | points kept | max kept vs asked | rays per point | voxel leaf [mm] |",
             "|---:|---|" + "---:|" * (len(CHECKPOINTS) + 4)]
    for (fraction, strategy), rows in sorted(runs.items(), key=lambda kv: (kv[0][0], list(STYLE).index(kv[0][1]))):
        at = [rows[min(f, len(rows)) - 1] for f in CHECKPOINTS]
        deviation = max(abs(int(r["kept"]) - int(r["asked"])) / max(1, int(r["asked"])) for r in rows)
        spread = sum(int(r["columns"]) for r in rows) / max(1, sum(int(r["kept"]) for r in rows))
        leaves = [float(r["leaf_m"]) * 1e3 for r in rows]
        leaf = f"{min(leaves):.1f}-{max(leaves):.1f}" if max(leaves) > 0 else "-"
        lines.append(f"| {fraction:.0%} | {strategy} | " + " | ".join(f"{float(r['quality']):.3f}" for r in at) +
                     f" | {int(rows[-1]['points']):,} | {deviation:.1%} | {spread:.3f} | {leaf} |")
    return "\n".join(lines) + "\n"


def main(out_dir):
    runs = read_runs(os.path.join(out_dir, "filter.csv"))
    for fraction in sorted({f for f, _ in runs}):
        print("wrote", plot(runs, fraction, out_dir))
    text = table(runs)
    open(os.path.join(out_dir, "table.md"), "w").write(text)
    print(text, end="")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
