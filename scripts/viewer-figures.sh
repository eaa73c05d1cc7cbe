#!/usr/bin/env bash
# Regenerates the pictures of docs/viewer.md by running `foveal view` under a virtual display
# (Xvfb, Mesa's software OpenGL): scripts/viewer-figures.sh [BUILD_DIR]
# Needs ../shared/data (the dragon, the Conference Room, the EyeLink recording) and xvfb-run.
# Takes about a minute on two cores.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/scripts/pictures.sh"
figures_setup viewer-figures "${1:-}" xvfb-run
[[ -d $data/scenes ]] || { echo "viewer-figures: $data/scenes is absent" >&2; exit 1; }
mkdir -p "$images"
cd "$root"
view() { xvfb-run -a -s '-screen 0 2400x1200x24' "$foveal" view "$@"; }

# Foveated AO on the dragon with the ROI contours and the AO budget, the whole window
view --scene scenes/dragon-box.json --camera camera1 --gaze 418,292 --overlays gaze,contours,budget \
  --frames 2 --screenshot "$images/view-foveated.png" --window-screenshot "$images/view-window.png"
# Foveated | reference | difference × 8, the gaze at the top-left corner
view --scene scenes/dragon-box.json --camera camera1 --size 560x350 --gaze 40,40 --mode side-by-side \
  --overlays gaze,contours --frames 2 --screenshot "$images/view-side-by-side.png"
# The simulated eye following the EyeLink recording (4x real time): the sharp region and the scan path
view --scene scenes/conference.json --camera table --gaze "$data/gaze/eyelink/monoRemote500.asc" --speed 4 --mode vision \
  --eye glaucoma:0.5 --overlays gaze,scanpath,sharp --frames 400 --screenshot "$images/view-vision.png"
rm -f "$images"/view-*.json
echo "viewer-figures: wrote $images/view-*.png"
