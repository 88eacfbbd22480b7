#!/usr/bin/env python3
"""Where should the sensor look next? One real Kinect frame's improvement map over its colour image.

Loads a 7-Scenes frame (depth PNG in millimetres, colour PNG, camera-intrinsics.txt) from the shared data
folder, fuses it into a kinect_v1 grid built from the intrinsics, and draws the improvement map over the
colour image with the best regions marked. Without a display (or with --out) the figure is saved as PNG
with matplotlib's Agg backend. Without the data folder it falls back to the built-in sample scene.

    PYTHONPATH=build/python python3 samples/python/improvement_overlay.py [--frame 150] [--out out/python]
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

import occ_improve as oi

KITCHEN = Path("sequences/7scenes_redkitchen")


def default_data_dir() -> Path:
    env = os.environ.get("OCC_IMPROVE_DATA_DIR")
    return Path(env) if env else Path(__file__).resolve().parents[2].parent / "shared" / "data"


def load_frame(data: Path, index: int):
    """(depth metres, colour image or None, intrinsics, title)."""
    folder = data / KITCHEN
    depth_png = folder / "frames" / f"frame-{index:06d}.depth.png"
    if not depth_png.exists():
        print(f"{depth_png} not found: using the built-in sample scene (set OCC_IMPROVE_DATA_DIR)")
        depth, intrinsics = oi.sample_depth()
        return depth, None, intrinsics, "built-in sample"
    import matplotlib.pyplot as plt

    colour = plt.imread(folder / "frames" / f"frame-{index:06d}.color.png")
    intrinsics = oi.read_intrinsics(folder / "camera-intrinsics.txt")
    return oi.read_depth_png(depth_png), colour, intrinsics, f"7-Scenes redkitchen frame {index}"


def draw(mapper: oi.Mapper, depth, colour, title: str):
    import matplotlib.pyplot as plt

    improvement = mapper.improvement()
    regions = mapper.regions()[:5]
    figure, axis = plt.subplots(figsize=(9, 6.5))
    background = colour if colour is not None else np.clip(depth / 5.0, 0, 1)
    # The colour camera is not registered to the depth camera (7-Scenes): the overlay is approximate.
    axis.imshow(background, cmap="gray", extent=(0, mapper.width, mapper.height, 0))
    shown = axis.imshow(improvement, cmap="RdYlGn_r", vmin=-0.3, vmax=0.33, alpha=0.55,
                        extent=(0, mapper.width, mapper.height, 0))
    figure.colorbar(shown, ax=axis, fraction=0.035, label="expected improvement of one more measurement")
    for rank, region in enumerate(regions, 1):
        centre = (region.centre_u, region.centre_v)  # a ray of the region, in the image's columns and rows
        axis.plot(*centre, "o", mfc="none", mec="white", ms=14, mew=2)
        axis.annotate(str(rank), centre, color="white", fontsize=12, ha="center", va="center")
    axis.set_title(f"{title}: best regions (circles), red = worth measuring again")
    axis.set_axis_off()
    return figure


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=default_data_dir(), help="the shared data folder")
    parser.add_argument("--frame", type=int, default=150, help="7-Scenes frame number (150-199)")
    parser.add_argument("--out", type=Path, help="save improvement_overlay.png here instead of showing it")
    args = parser.parse_args()
    headless = args.out is not None or not os.environ.get("DISPLAY")
    if headless:
        import matplotlib

        matplotlib.use("Agg")  # no display: draw into a file
    depth, colour, intrinsics, title = load_frame(args.data, args.frame)
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    report = mapper.insert_depth(depth, intrinsics)
    stop = mapper.stop_signal()
    print(f"{title}: {report.insertion.points_inserted} points in {report.insertion.seconds * 1e3:.0f} ms, "
          f"improvement in {report.improvement_seconds * 1e3:.0f} ms; {stop.reason}")
    for rank, region in enumerate(mapper.regions()[:5], 1):
        print(f"  region {rank}: summed {region.summed_improvement:.1f} over {region.area_columns} rays, "
              f"mean depth {region.mean_depth_m:.2f} m")
    figure = draw(mapper, depth, colour, title)
    if headless:
        out = args.out or Path("out/python")
        out.mkdir(parents=True, exist_ok=True)
        figure.savefig(out / "improvement_overlay.png", dpi=100, bbox_inches="tight")
        print(f"wrote {out / 'improvement_overlay.png'}")
    else:
        import matplotlib.pyplot as plt

        plt.show()


if __name__ == "__main__":
    main()
