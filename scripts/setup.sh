#!/usr/bin/env bash
# Idempotent set-up for a fresh machine: Vulkan (lavapipe) where no NVIDIA driver exists, then .venv.
# The second run only checks stamps, so it takes a second or two.
set -euo pipefail
cd "$(dirname "$0")/.."

log() { printf '[setup] %s\n' "$*"; }

find_python() {
  for c in "${PYTHON:-}" python3.12 "$HOME/.pyenv/versions/3.12"*/bin/python3.12 /usr/local/bin/python3.12 /usr/bin/python3.12; do
    [ -n "$c" ] || continue
    if command -v "$c" >/dev/null 2>&1 && "$c" -c 'import sys; assert sys.version_info[:2] >= (3, 12)' 2>/dev/null; then
      command -v "$c"; return 0
    fi
  done
  # pyenv shims exist but refuse to run when 3.12 is not the selected version
  if command -v pyenv >/dev/null 2>&1; then
    v=$(pyenv versions --bare 2>/dev/null | grep -E '^3\.1[2-9]' | head -n1 || true)
    [ -n "$v" ] && { echo "$(pyenv root)/versions/$v/bin/python3"; return 0; }
  fi
  return 1
}

have_nvidia_vulkan() {
  ls /usr/share/vulkan/icd.d/nvidia_icd.json /etc/vulkan/icd.d/nvidia_icd.json \
     /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json 2>/dev/null | grep -q .
}

lavapipe_version() {  # prints the installed mesa-vulkan-drivers version, or nothing
  dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true
}

install_vulkan() {
  if have_nvidia_vulkan; then log "NVIDIA Vulkan driver found; skipping lavapipe"; return; fi
  v=$(lavapipe_version)
  if [ -n "$v" ] && dpkg --compare-versions "$v" ge 24.3 && ldconfig -p | grep -q libvulkan.so.1; then
    log "lavapipe $v present"; return
  fi
  if ! command -v apt-get >/dev/null 2>&1; then
    log "WARNING: no apt-get; install a Vulkan driver (Mesa lavapipe >= 24.3) yourself for rendering"; return
  fi
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  . /etc/os-release
  codename="${VERSION_CODENAME:-bookworm}"
  list=/etc/apt/sources.list.d/realm-ms-backports.sources
  if [ ! -f "$list" ]; then
    # Derive the backports source from the machine's own Debian source (mirror, keyring), never a fixed host.
    src=$(ls /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)
    if [ -n "$src" ]; then
      uri=$(awk '/^URIs:/{print $2; exit}' "$src")
      key=$(awk '/^Signed-By:/{print $2; exit}' "$src")
    else
      uri=$(awk '$1=="deb" && $0 !~ /security/ {for(i=2;i<=NF;i++) if ($i ~ /^(https?|file):/) {print $i; exit}}' /etc/apt/sources.list)
      key=/usr/share/keyrings/debian-archive-keyring.gpg
    fi
    log "adding ${codename}-backports from $uri"
    printf 'Types: deb\nURIs: %s\nSuites: %s-backports\nComponents: main\nSigned-By: %s\n' \
      "$uri" "$codename" "${key:-/usr/share/keyrings/debian-archive-keyring.gpg}" | $SUDO tee "$list" >/dev/null
  fi
  $SUDO apt-get update -qq -o Dir::Etc::sourcelist=/dev/null -o Dir::Etc::sourceparts=/etc/apt/sources.list.d >/dev/null || $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq -t "${codename}-backports" mesa-vulkan-drivers libvulkan1 >/dev/null
  log "installed lavapipe $(lavapipe_version)"
}

# pip's own chatter (index warnings of the machine's pip config, setuptools' editable-install notice)
# goes to .venv/pip-install.log; a failing install prints its tail and stops
quiet_pip() {
  if ! .venv/bin/python -m pip install -q "$@" >>.venv/pip-install.log 2>&1; then
    tail -n 40 .venv/pip-install.log >&2
    echo "ERROR: pip install $* failed; the whole log is .venv/pip-install.log" >&2
    exit 1
  fi
}

install_venv() {
  stamp=.venv/.realm-ms-stamp
  want=$(cat pyproject.toml scripts/setup.sh lerobot_env_realm/_distribution/pyproject.toml | sha256sum | cut -c1-16)
  if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ] && [ -x .venv/bin/python ]; then
    log ".venv up to date"; return
  fi
  if [ ! -x .venv/bin/python ]; then
    py=$(find_python) || { echo "ERROR: Python >= 3.12 not found. Install it (e.g. 'pyenv install 3.12') or set PYTHON=/path/to/python3.12" >&2; exit 1; }
    log "creating .venv with $py"
    "$py" -m venv .venv
  fi
  log "installing realm-ms and its dependencies (first time: several minutes)"
  .venv/bin/python -m pip install -q --upgrade pip >/dev/null 2>&1 || true
  quiet_pip -e ".[dev]"
  # metadata-only distribution named lerobot_env_*: LeRobot auto-imports such distributions, which
  # registers the `realm` env type for `lerobot-eval --env.type=realm` (docs/lerobot.md)
  quiet_pip --no-deps ./lerobot_env_realm/_distribution
  # the wire-compatibility tests of our openpi client talk to the reference client; it pins numpy<2
  # for its own extras only, so it is installed without its dependencies
  quiet_pip --no-deps "openpi-client==0.1.2"
  echo "$want" > "$stamp"
}

install_vulkan
install_venv
log "ready"
