#!/usr/bin/env bash
# Regenerates the pictures of docs/vision.md by running foveal (nothing is drawn by hand):
#   scripts/vision-figures.sh [BUILD_DIR]
# Needs ../shared/data (the Conference Room, the EyeLink recording) and ffmpeg (to put pictures
# side by side). Takes about two minutes on two cores.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/scripts/pictures.sh"
figures_setup vision-figures "${1:-}" ffmpeg
[[ -d $data/scenes/conference ]] || { echo "vision-figures: $data/scenes/conference is absent" >&2; exit 1; }
mkdir -p "$images"
cd "$root"


scene=scenes/conference.json
echo "vision-figures: the paper's Figure 3 (steps 1, 4, 20, 69)"
"$foveal" simulate --scene $scene --steps 69 --save-steps 1,4,20,69 -o "$work/steps" --stats "$work/steps.json" -q
stack "$images/vision-steps.png" 512 2 "$work"/steps/step_000{1,4}.png "$work"/steps/step_00{20,69}.png

echo "vision-figures: the paper's Figure 2 (scan paths, healthy and glaucoma)"
"$foveal" simulate --scene $scene --steps 20 --save-steps '' -o "$work/healthy" -q
"$foveal" simulate --scene $scene --steps 20 --save-steps '' --eye glaucoma:0.8 -o "$work/glaucoma" -q
stack "$images/vision-scanpaths.png" 512 2 "$work/healthy/scanpath.png" "$work/glaucoma/scanpath.png"

echo "vision-figures: eye defects after 20 steps with the same fixations"
defects=(healthy myopia:-3 presbyopia:60 astigmatism:2@45)
pictures=()
for eye in "${defects[@]}"; do
  out="$work/eye-${eye//[:@]/_}"
  "$foveal" simulate --scene $scene --steps 20 --save-steps '' --eye "$eye" -o "$out" -q
  pictures+=("$out/perceived.png")
done
stack "$images/vision-eyes.png" 512:384:300:330 2 "${pictures[@]}"  # the table, at full resolution

echo "vision-figures: real gaze (EyeLink fixations) before and after a recorded blink"
"$foveal" simulate --scene $scene --gaze "$data/gaze/eyelink/monoRemote500.asc" --fixation tracker --steps 75 \
  --save-steps 71,72 -o "$work/eyelink" --stats "$work/eyelink.json" -q
stack "$images/vision-eyelink-blink.png" 512:384:300:330 2 "$work/eyelink/step_0071.png" "$work/eyelink/step_0072.png"
cp "$work/eyelink/scanpath.png" "$images/vision-eyelink-scanpath.png"

echo "vision-figures: the blur against the thin-lens reference (builtin:box, 150 mm pupil)"
"$foveal" bench blur --scene builtin:box --pupil 150 --size 512x384 --lens-samples 128 --images "$work/lens" > /dev/null
stack "$images/vision-thin-lens.png" 400 3 "$work/lens/pinhole.png" "$work/lens/near-approximation.png" "$work/lens/near-reference.png"

python3 - "$work" <<'EOF' || true
import json, sys
work = sys.argv[1]
for name in ("steps", "eyelink"):
    j = json.load(open(f"{work}/{name}.json"))
    print(name, "sharp fraction by step:", " ".join(f"{s['step']}:{100 * s['sharp_fraction']:.1f}%" for s in j["steps"] if s["step"] in (1, 4, 20, 69, 70, 71, 72, 73, 75)))
EOF
echo "vision-figures: wrote $images/vision-*.png"
