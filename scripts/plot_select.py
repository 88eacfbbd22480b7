#!/usr/bin/python3
"""Plots and the target table of make select-eval, from the per-scene CSVs occ_select_eval writes.

- OUT_DIR/<scene>.png: quality (share of scene rays whose predicted depth lies within 2 sigma of the
  scene's) against points acquired, one panel per budget, one curve per strategy, (a)'s full frames as
  squares, the first shot whose plan said stop as a triangle;
- OUT_DIR/targets.md: per scene and budget, the points (in full frames) each strategy needs to reach 95%
  of the quality of 5 full frames, the best of (d)-(f) against half of (b)'s, its smallest margin over
  (b) at equal points, its stop point against the knee (the first point within 99% of its best), and
  the best guided run (any of (d)-(g), any predictor) against the best uniform run (any predictor):
  the issue's targets (half of uniform's points, 0.3 frames), the smallest margin at equal points, the
  stop against the knee and the calibration r (expected gain against the change of rays within 2 sigma).

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
    "g_coarse_to_fine": ("(g) coarse-to-fine", "tab:red", "-"),
    "g_improvement": ("(g) by improvement only", "tab:purple", ":"),
    "g_residual": ("(g) by residual only", "tab:pink", ":"),
    "g_triangles": ("(g) by triangles", "tab:olive", "-"),
    "o_oracle": ("(o) oracle: reads the scene (a reference)", "black", ":"),
}
# Runs scored with the linear predictor are named <strategy>_linear: same colour, dashed, thinner.
STYLE.update({s + "_linear": (label + ", linear", colour, "--") for s, (label, colour, line) in list(STYLE.items())})
GUIDED = [s for s in STYLE if s[0] in "defg"]  # not (o): it reads the scene
UNIFORM = [s for s in STYLE if s.startswith("b_")]


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
            if stops and not strategy.startswith("d_guided"):
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


def pearson(xy):
    n = len(xy)
    if n < 2:
        return None
    mx, my = sum(x for x, _ in xy) / n, sum(y for _, y in xy) / n
    vx, vy = sum((x - mx) ** 2 for x, _ in xy), sum((y - my) ** 2 for _, y in xy)
    return sum((x - mx) * (y - my) for x, y in xy) / (vx * vy) ** 0.5 if vx > 0 and vy > 0 else None


def target_rows(path):
    """One markdown row per budget of a scene: the best uniform run (any predictor) against the best
    guided run (any predictor), the issue's targets, the stop against the knee and the calibration."""
    runs, scene, full, frame_rays, budgets, target = load_scene(path)
    fmt = lambda v: "-" if v is None else f"{v:.2f}"
    out = []
    for budget in budgets:
        need = {s: first_reaching(runs[(s, budget)], target, frame_rays) for s in STYLE if (s, budget) in runs}
        pick = lambda names: min((s for s in names if need.get(s) is not None), key=lambda s: need[s], default=None)
        best_uniform = pick(UNIFORM) or next((s for s in UNIFORM if (s, budget) in runs), None)
        best = pick(GUIDED) or next((s for s in GUIDED if (s, budget) in runs), None)
        if best is None or best_uniform is None:
            continue  # a partial run (-strategies without both kinds)
        uniform_at = {}
        for s in UNIFORM:
            for r in runs.get((s, budget), []):
                k = int(r["rays_asked"])
                uniform_at[k] = max(uniform_at.get(k, 0.0), float(r["quality"]))
        rows = runs[(best, budget)]
        margin = min((float(r["quality"]) - uniform_at[int(r["rays_asked"])] for r in rows
                      if int(r["rays_asked"]) in uniform_at), default=float("nan"))
        stop = next((int(r["rays_asked"]) / frame_rays for r in rows if r["plan_stop"] == "1"), None)
        knee = first_reaching(rows, 0.99 * max(float(r["quality"]) for r in rows), frame_rays)
        half = need.get(best) is not None and need.get(best_uniform) is not None and need[best] <= 0.5 * need[best_uniform]
        small = need.get(best) is not None and need[best] <= 0.3
        stop_ok = stop is not None and knee is not None and abs(stop - knee) <= 0.1 * knee
        pairs = [(float(r["expected_gain"]), float(r["realised_good_rays"])) for r in rows]
        # Also without the first checkpoint: the first shot's gain dwarfs every later one, and one point
        # that far out carries r by itself.
        r_cal, r_later = pearson(pairs), pearson(pairs[1:]) if len(pairs) > 2 else None
        out.append(f"| {scene} | {100 * budget / frame_rays:.0f}% | {target:.3f} | {best_uniform} {fmt(need.get(best_uniform))} | "
                   f"{best} {fmt(need.get(best))} | {'yes' if half else 'no'} | {'yes' if small else 'no'} | "
                   f"{margin:+.3f} | {fmt(stop)} / {fmt(knee)} | {'yes' if stop_ok else 'no'} | "
                   f"{'-' if r_cal is None else f'{r_cal:.2f}'} | {'-' if r_later is None else f'{r_later:.2f}'} | "
                   + " ".join(f"{s}={fmt(v)}" for s, v in sorted(need.items())) + " |")
    return out


def write_targets(paths, out_dir):
    header = ["| scene | budget | 95% of 5 frames | best uniform [frames] | best guided [frames] | <= half | <= 0.3 frames | "
              "min margin over best uniform | stop / knee [frames] | stop within 10% | calibration r | "
              "r without the first checkpoint | every run [frames] |",
              "|---|---:|---:|---|---|---|---|---:|---:|---|---:|---:|---|"]
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
