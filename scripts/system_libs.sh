#!/usr/bin/env bash
# Make sure the shared libraries for headless rendering (EGL/OSMesa via Mesa) and for video
# decoding (FFmpeg, used by torchcodec in lerobot's loader) are present.
# Installs them with apt-get when run as root; otherwise names what is missing and fails.
set -euo pipefail

# soname -> Debian package that provides it
declare -A NEED=(
  [libEGL.so.1]=libegl1
  [libEGL_mesa.so.0]=libegl-mesa0
  [libgbm.so.1]=libgbm1
  [libOSMesa.so.8]=libosmesa6
  [libavcodec.so]=ffmpeg
  [libavformat.so]=ffmpeg
  [libswscale.so]=ffmpeg
)
# libgl1-mesa-dri ships the llvmpipe driver itself (a file, not a soname).
DRI=(/usr/lib/*/dri/swrast_dri.so /usr/lib/dri/swrast_dri.so)

missing=()
for so in "${!NEED[@]}"; do
  ldconfig -p | grep -q "${so}" || missing+=("${NEED[$so]}")
done
found_dri=0
for f in "${DRI[@]}"; do [ -e "$f" ] && found_dri=1; done
[ "$found_dri" = 1 ] || missing+=(libgl1-mesa-dri)

if [ "${#missing[@]}" -eq 0 ]; then
  exit 0
fi
pkgs=$(printf '%s\n' "${missing[@]}" | sort -u | tr '\n' ' ')
if [ "$(id -u)" -eq 0 ] && command -v apt-get >/dev/null; then
  echo "installing system libraries: ${pkgs}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  # shellcheck disable=SC2086
  apt-get install -y -qq --no-install-recommends ${pkgs} >/dev/null
else
  echo "error: missing system libraries for headless rendering/video; install them with: sudo apt-get install -y ${pkgs}" >&2
  exit 1
fi
