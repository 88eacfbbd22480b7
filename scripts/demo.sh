#!/usr/bin/env bash
# The main job on the built-in sample: occ_improve_map on the generated Kinect-like frame.
set -euo pipefail
build=${1:-build}
out=out/demo
mkdir -p "$(dirname "$out")"
"$build/pcl_tools/occ_improve_map" -sample -o "$out"
echo
echo "Outputs in $out/:"
ls -l "$out"
echo "Open $out/improvement.png with $out/legend.png beside it (README: 'Reading the demo's improvement image');"
echo "pcl_viewer $out/surface.pcd shows the surface with its probability and improvement fields."
