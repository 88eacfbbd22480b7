#!/usr/bin/python3
"""Plots and the target table of make select-eval, from the per-scene CSVs occ_select_eval writes.

- OUT_DIR/<scene>.png: quality (share of scene rays whose predicted depth lies within 2 sigma of the
  scene's) against points acquired, one panel per budget, one curve per strategy, (a)'s full frames as
  squares, the first shot whose plan said stop as a triangle;
- OUT_DIR/targets.md: per scene and budget, the points (in full frames) each strategy needs to reach 95%
  of the quality of 5 full frames, the best of (d)-(f) against half of (b)'s, its smallest margin over
  (b) at equal points, its stop point against the knee (the first point within 99% of its best), and
  the points (b) and the best need to reach the quality of 5 full frames itself.

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


def load_scene(path):
    """A scene's runs, its name, strategy (a)'s rows, the rays of a full frame, the budgets of the other
    strategies and the target (95% of the quality of 5 full frames)."""
    runs = read_runs(path)
    scene = os.path.splitext(os.path.basename(path))[0]
    full = next(rows for (s, _), rows in runs.items() if s == "a_full")
    budgets = sorted({b for (s, b) in runs if s != "a_full"})
    return runs, scene, full, int(full[0]["budget_rays"]), budgets, 0.95 * float(full[-1]["quality"])


def plot_scene(path):
    runs, scene, full, frame_rays, budgets, target = load_scene(path)
    fig, axes = plt.subplots(1, len(budgets), figsize=(5 * len(budgets), 4), sharey=True, squeeze=False)
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


def first_reaching(rows, target, frame_rays):
    for r in rows:
        if float(r["quality"]) >= target:
            return int(r["rays_asked"]) / frame_rays
    return None


def target_rows(path):
    """One markdown row per budget of a scene."""
    runs, scene, full, frame_rays, budgets, target = load_scene(path)
    fmt = lambda v: "-" if v is None else f"{v:.2f}"
    out = []
    for budget in budgets:
        need = {s: first_reaching(runs.get((s, budget), []), target, frame_rays) for s in STYLE}
        guided = {s: need[s] for s in ("d_guided", "e_returns", "f_reacquire") if need[s] is not None}
        best = min(guided, key=guided.get) if guided else "e_returns"
        uniform = {int(r["rays_asked"]): float(r["quality"]) for r in runs[("b_uniform", budget)]}
        margin = min(float(r["quality"]) - uniform[int(r["rays_asked"])] for r in runs[(best, budget)]
                     if int(r["rays_asked"]) in uniform)
        rows = runs[(best, budget)]
        stop = next((int(r["rays_asked"]) / frame_rays for r in rows if r["plan_stop"] == "1"), None)
        top = max(float(r["quality"]) for r in rows)
        knee = first_reaching(rows, 0.99 * top, frame_rays)
        full_quality = float(full[-1]["quality"])
        match = {s: first_reaching(runs.get((s, budget), []), full_quality, frame_rays) for s in ("b_uniform", best)}
        met = need[best] is not None and need["b_uniform"] is not None and need[best] <= 0.5 * need["b_uniform"]
        stop_ok = stop is not None and knee is not None and abs(stop - knee) <= 0.1 * knee
        out.append(f"| {scene} | {100 * budget / frame_rays:.0f}% | {target:.3f} | "
                   + " | ".join(fmt(need[s]) for s in STYLE)
                   + f" | {best[0]} | {'yes' if met else 'no'} | {margin:+.3f} | {fmt(stop)} / {fmt(knee)} | "
                   + f"{'yes' if stop_ok else 'no'} | {fmt(match['b_uniform'])} / {fmt(match[best])} |")
    return out


def write_targets(paths, out_dir):
    header = ["| scene | budget | 95% of 5 frames | (b) | (c) | (d) | (e) | (f) | best | <= half of (b) | "
              "min margin over (b) | stop / knee [frames] | stop within 10% | 100% of 5 frames: (b) / best |",
              "|---|---:|---:|---:|---:|---:|---:|---:|---|---|---:|---:|---|---:|"]
    lines = header + [row for p in paths for row in target_rows(p)]
    with open(os.path.join(out_dir, "targets.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote", os.path.join(out_dir, "targets.md"))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    paths = [p for p in sorted(glob.glob(os.path.join(sys.argv[1], "*.csv"))) if not p.endswith("summary.csv")]
    if not paths:
        sys.exit(f"plot_select: no scene CSV in {sys.argv[1]}")
    for p in paths:
        print("wrote", plot_scene(p))
    write_targets(paths, sys.argv[1])


if __name__ == "__main__":
    main()
