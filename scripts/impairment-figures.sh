#!/usr/bin/env bash
# Regenerates the pictures of docs/impairments.md by running foveal (nothing is drawn by hand):
#   scripts/impairment-figures.sh [BUILD_DIR]
# Needs ../shared/data (Sponza, the natural images) and ffmpeg (to put pictures side
# by side). Takes about a minute on two cores.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/scripts/pictures.sh"
figures_setup impairment-figures "${1:-}" ffmpeg
[[ -d $data/scenes/sponza && -d $data/images ]] || { echo "impairment-figures: $data is absent" >&2; exit 1; }
mkdir -p "$images"
cd "$root"

field=examples/eyes/glaucoma-24-2.csv
echo "impairment-figures: a 24-2 arcuate defect and its interpolated map (right eye)"
"$foveal" perceive builtin:amsler -o "$work/unused.png" --eye "field:24-2:$field+field-view:OD" --field-map "$images/impair-field-map.png" -q

echo "impairment-figures: textured Sponza seen with it at two fixations"
"$foveal" simulate --scene scenes/sponza.json --steps 2 --save-steps 1,2 --seed 3 \
  --eye "field:24-2:$field+field-view:OD" -o "$work/arcuate" --stats "$work/arcuate.json" -q
stack "$images/impair-sponza-fixations.png" 512 2 "$work"/arcuate/step_000{1,2}.png

echo "impairment-figures: colour-vision deficiency (Machado et al. 2009, severity 1)"
img="$data/images/building.jpg"
"$foveal" perceive "$img" -o "$work/cvd-none.png" --no-optics -q
for t in protan deutan tritan; do "$foveal" perceive "$img" -o "$work/cvd-$t.png" --eye "cvd:$t:1" --no-optics -q; done
stack "$images/impair-cvd.png" 400 4 "$work"/cvd-{none,protan,deutan,tritan}.png

echo "impairment-figures: forward scatter around bright lamps (CIE 2002 glare, lens yellowing)"
"$foveal" perceive builtin:lamps -o "$work/glare-25.png" --no-optics -q
"$foveal" perceive builtin:lamps -o "$work/glare-70.png" --eye age:70+glare --no-optics -q
"$foveal" perceive builtin:lamps -o "$work/glare-c5.png" --eye age:70+cataract:0.5 --no-optics -q
"$foveal" perceive builtin:lamps -o "$work/glare-c10.png" --eye age:70+cataract:1 --no-optics -q
stack "$images/impair-glare.png" 480 2 "$work"/glare-{25,70,c5,c10}.png

echo "impairment-figures: macular degeneration and its Amsler grid"
"$foveal" perceive builtin:amsler -o "$work/amsler.png" --eye examples/eyes/amd-patient.json -q
"$foveal" perceive "$data/images/baboon.jpg" -o "$work/amd.png" --eye examples/eyes/amd-patient.json -q
stack "$images/impair-amd.png" 440 2 "$work/amsler.png" "$work/amd.png"

echo "impairment-figures: the paper's glaucoma model beside the field-loss one (20 steps, same seed)"
"$foveal" simulate --scene scenes/sponza.json --steps 20 --save-steps '' --eye glaucoma:0.8 -o "$work/paper" -q
"$foveal" simulate --scene scenes/sponza.json --steps 20 --save-steps '' --eye "glaucoma:0.8+field:24-2:$field+field-view:OD" -o "$work/field" -q
stack "$images/impair-glaucoma-models.png" 512 2 "$work/paper/perceived.png" "$work/field/perceived.png"
echo "impairment-figures: wrote docs/images/impair-*.png"
