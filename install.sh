#!/usr/bin/env bash
# Install crowdwalk into the virtual environment .venv next to this file (created if absent,
# reused if present) on a Debian/Ubuntu machine with Python >= 3.11; then
#   . .venv/bin/activate      # puts `crowdwalk` and the environment's python3 on PATH
# Never installs into the system Python (PEP 668 "externally managed" systems refuse that).
# Each step is one function, called in order at the bottom; add a step there.
set -euo pipefail
cd "$(dirname "$0")"

VENV="$PWD/.venv"
LOG="$VENV/install.log"
# Debian packages the features need (installed as root or with sudo, else named for an
# administrator). Add a feature's packages here with a comment saying what needs them.
APT_PACKAGES=(
  libegl1 libegl-mesa0 libgl1-mesa-dri  # off-screen rendering (pyvista/VTK over EGL + Mesa)
  chromium  # headless browser of the `crowdwalk view --web` test (tests/viz/test_web.py)
)

say() { echo "install.sh: $*"; }

find_python() {  # PY: the first Python >= 3.11 on PATH
  for cand in "${PYTHON:-python3}" python3.13 python3.12 python3.11; do
    if command -v "$cand" >/dev/null 2>&1 &&
       "$cand" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
      PY=$(command -v "$cand"); say "using $PY ($("$PY" -V 2>&1))"; return
    fi
  done
  say "crowdwalk needs Python >= 3.11 (python3 is $(python3 -V 2>&1 || echo absent))." >&2
  say "  Install one (Debian 12 / Ubuntu 24.04: apt-get install python3 python3-venv)" >&2
  exit 1
}

need_venv_module() {  # Debian ships ensurepip (which venv needs) in pythonX.Y-venv
  if [ ! -x "$VENV/bin/python" ] && ! "$PY" -c 'import ensurepip, venv' 2>/dev/null; then
    APT_PACKAGES+=("python$("$PY" -c 'import sys; print("%d.%d" % sys.version_info[:2])')-venv")
  fi
}

apt_packages() {  # install the missing APT_PACKAGES, or say which to ask for
  command -v dpkg-query >/dev/null 2>&1 || return 0
  local missing=() p sudo=""
  for p in "${APT_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && { say "Debian packages present: ${APT_PACKAGES[*]}"; return; }
  if [ "$(id -u)" -ne 0 ]; then command -v sudo >/dev/null 2>&1 && sudo="sudo" || sudo="none"; fi
  if [ "$sudo" != "none" ] && command -v apt-get >/dev/null 2>&1; then
    say "installing Debian packages: ${missing[*]} (apt-get)"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
  else
    say "these Debian packages are missing: ${missing[*]}" >&2
    say "  Ask an administrator to run: apt-get install ${missing[*]}" >&2
    say "  Without the GL packages everything but rendering works; render tests skip." >&2
  fi
}

make_venv() {
  if [ -x "$VENV/bin/python" ]; then say "reusing the virtual environment $VENV"; return; fi
  say "creating the virtual environment $VENV"
  if ! "$PY" -m venv "$VENV"; then
    say "could not create $VENV; on Debian/Ubuntu: apt-get install python3-venv" >&2
    exit 1
  fi
}

pip_install() {  # one line per package pip fetches; the whole pip output goes to $LOG
  say "installing crowdwalk and its dependencies into $VENV (a few minutes; log: $LOG)"
  "$VENV/bin/python" -m pip install --quiet --upgrade pip >"$LOG" 2>&1 ||
    { tail -n 20 "$LOG" >&2; exit 1; }
  if ! PYTHONUNBUFFERED=1 "$VENV/bin/python" -m pip install --progress-bar off -e ".[dev]" 2>&1 |
       tee -a "$LOG" |
       { grep -E --line-buffered '^(Collecting|Successfully installed)' |
         sed -u 's/^\(.\{1,98\}\).*$/  \1/' || true; }; then
    say "pip failed; the end of $LOG:" >&2; tail -n 20 "$LOG" >&2; exit 1
  fi
  # embreex: faster mesh ray queries where a wheel exists; rtree (a base dependency) otherwise.
  "$VENV/bin/python" -m pip install --quiet -e ".[fast]" >>"$LOG" 2>&1 &&
    say "optional embreex installed (faster mesh terrain queries)" ||
    say "optional embreex unavailable here; mesh terrain uses rtree"
}

warm_kernels() {  # compile the numba kernels now: the first run loads them (crowdwalk.warm)
  say "compiling the numba kernels once (about a minute)"
  if "$VENV/bin/python" -m crowdwalk.warm >>"$LOG" 2>&1; then say "kernels compiled"
  else say "kernel warm-up failed (log: $LOG); the first run compiles them instead" >&2; fi
}

find_python
need_venv_module
apt_packages
make_venv
pip_install
warm_kernels
say "done: $("$VENV/bin/crowdwalk" --version). Activate the environment with: . .venv/bin/activate"
