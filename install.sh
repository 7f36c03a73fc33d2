#!/usr/bin/env bash
# Install crowdwalk and everything it needs on a Debian/Ubuntu machine with Python >= 3.11.
# Off-screen rendering (pyvista/VTK) needs an EGL + Mesa GL stack; without it VTK segfaults.
set -euo pipefail
cd "$(dirname "$0")"

gl_pkgs=(libegl1 libegl-mesa0 libgl1-mesa-dri)
missing=()
if command -v dpkg-query >/dev/null 2>&1; then
  for p in "${gl_pkgs[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
  done
fi
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" -eq 0 ]; then SUDO=""; elif command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else SUDO="none"; fi
  if [ "$SUDO" != "none" ] && command -v apt-get >/dev/null 2>&1; then
    echo "install.sh: installing the GL stack for off-screen rendering: ${missing[*]}"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
  else
    echo "install.sh: off-screen rendering needs the Debian packages ${missing[*]}." >&2
    echo "  Ask an administrator to run: apt-get install ${missing[*]}" >&2
    echo "  Everything except rendering works without them; render tests are skipped." >&2
  fi
fi

python3 -m pip install --quiet --upgrade pip
python3 -m pip install --quiet -e ".[dev,fast]"
echo "install.sh: crowdwalk installed ($(python3 -m pip show crowdwalk 2>/dev/null | grep ^Version))."
