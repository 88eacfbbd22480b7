"""scripts/plot_select.py's targets table (make select-eval's targets.md), read back from a scene CSV written
here: the tools' default strategy, g_triangles, counts as a guided run, and every figure of its row is the
one the CSV implies (points to the target, the issue's two ratios, the margin, the stop and knee, r)."""
import csv
import importlib.util
from pathlib import Path

import pytest

pytest.importorskip("matplotlib", reason="plot_select.py draws with matplotlib (Debian: python3-matplotlib)")

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "plot_select.py"
COLUMNS = ["scene", "strategy", "budget_rays", "shot", "rays_asked", "returns", "quality", "coverage",
           "mean_abs_error_m", "expected_gain", "realised_good_rays", "plan_stop"]


def load_script():
    spec = importlib.util.spec_from_file_location("plot_select", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def write_scene(path):
    """A frame of 100 rays; 5 full frames end at quality 0.96 (target 0.912); shots of 5 rays."""
    rows = []
    for shot, quality in enumerate([0.90, 0.92, 0.93, 0.95, 0.96], 1):
        rows.append(["s", "a_full", 100, shot, 100 * shot, 100 * shot, quality, 1, 0, 0, 0, 0])
    uniform = [0.50, 0.70, 0.80, 0.85, 0.88, 0.90, 0.91, 0.915, 0.92, 0.92]
    triangles = [0.50, 0.80, 0.913, 0.93, 0.94, 0.945, 0.95, 0.95, 0.95, 0.95]
    gains = [9.0, 5.0, 3.0, 2.0, 1.0, 0.5, 0.4, 0.3, 0.2, 0.1]
    for shot in range(1, 11):
        rays = 5 * shot
        rows.append(["s", "b_uniform_linear", 5, shot, rays, rays, uniform[shot - 1], 1, 0, 0, 0, 0])
        stop = 1 if shot >= 8 else 0
        rows.append(["s", "g_triangles_linear", 5, shot, rays, rays, triangles[shot - 1], 1, 0, gains[shot - 1],
                     100 * gains[shot - 1] + shot, stop])
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(COLUMNS)
        writer.writerows(rows)
    return gains


def test_targets_row_of_the_triangles_strategy(tmp_path):
    gains = write_scene(tmp_path / "s.csv")
    (row,) = load_script().target_rows(str(tmp_path / "s.csv"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[0] == "s" and cells[1] == "5%" and cells[2] == "0.912"
    assert cells[3] == "b_uniform_linear 0.40"  # 0.915 first at 40 rays
    assert cells[4] == "g_triangles_linear 0.15"  # 0.913 at 15 rays
    assert cells[5] == "yes" and cells[6] == "yes"  # 0.15 <= half of 0.40; <= 0.3 frames
    margin = min(t - u for t, u in zip([0.50, 0.80, 0.913, 0.93, 0.94, 0.945, 0.95, 0.95, 0.95, 0.95],
                                        [0.50, 0.70, 0.80, 0.85, 0.88, 0.90, 0.91, 0.915, 0.92, 0.92]))
    assert cells[7] == f"{margin:+.3f}"
    assert cells[8] == "0.40 / 0.30"  # the first stop at shot 8; the knee: first >= 0.99 x 0.95 at shot 6
    assert cells[9] == "no"
    xs, ys = gains, [100 * g + shot for shot, g in enumerate(gains, 1)]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    r = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / (
        sum((x - mx) ** 2 for x in xs) * sum((y - my) ** 2 for y in ys)) ** 0.5
    assert cells[10] == f"{r:.2f}"
    xs, ys = xs[1:], ys[1:]  # the same without the first checkpoint
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    r_later = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / (
        sum((x - mx) ** 2 for x in xs) * sum((y - my) ** 2 for y in ys)) ** 0.5
    assert cells[11] == f"{r_later:.2f}"
