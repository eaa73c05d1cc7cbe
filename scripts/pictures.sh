# Shell helpers of the scripts that make the docs' pictures (sourced, not run).

# The common start of a pictures script NAME: root, build, foveal, data, images and a scratch
# folder `work` (removed on exit); stops with one line when foveal is not built or a TOOL is missing.
figures_setup() {  # figures_setup NAME BUILD_DIR TOOL...
  local name=$1
  build=${2:-$root/build}
  shift 2
  foveal="$build/foveal"
  data="$root/../shared/data"
  images="$root/docs/images"
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  [[ -x $foveal ]] || { echo "$name: $foveal not built (run scripts/setup.sh)" >&2; exit 1; }
  local tool
  for tool in "$@"; do command -v "$tool" > /dev/null || { echo "$name: $tool is needed (scripts/deps.sh installs it)" >&2; exit 1; }; done
}

# Pictures in a grid of COLUMNS, each scaled to WIDTH pixels across or cropped (ffmpeg's xstack)
stack() {  # stack OUT WIDTH COLUMNS IN...
  local out=$1 width=$2 columns=$3
  shift 3
  local n=$# inputs=() filter="" layout=""
  for f in "$@"; do inputs+=(-i "$f"); done
  # WIDTH may be a crop W:H:X:Y of the full-resolution pictures instead of a width to scale to
  local each="scale=$width:-2"
  [[ $width == *:* ]] && each="crop=$width"
  for ((k = 0; k < n; ++k)); do filter+="[$k]$each[s$k];"; done
  for ((k = 0; k < n; ++k)); do
    local x="0" y="0"
    for ((c = 0; c < k % columns; ++c)); do x+="+w$c"; done
    for ((r = 0; r < k / columns; ++r)); do y+="+h$((r * columns))"; done
    filter+="[s$k]"
    layout+="${layout:+|}${x}_${y}"
  done
  filter+="xstack=inputs=$n:layout=$layout:fill=white"
  ffmpeg -loglevel error -y "${inputs[@]}" -filter_complex "$filter" -frames:v 1 -update 1 "$out"
}
