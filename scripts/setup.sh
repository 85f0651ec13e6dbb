#!/usr/bin/env bash
# Set up centerart on Debian 12 (bookworm): system packages, a virtual environment in .venv, the package.
#   bash scripts/setup.sh          # runtime
#   bash scripts/setup.sh --dev    # + test and lint tools, and Ray (the cluster extra, which the tests exercise)
# Idempotent: a second run only checks that everything is there.
set -euo pipefail
cd "$(dirname "$0")/.."
extras=""
[[ "${1:-}" == "--dev" ]] && extras="[dev,cluster]"

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive

# SAPIEN renders on the CPU only with Mesa >= 24's lavapipe, which bookworm has in bookworm-backports.
# The backports source copies the machine's own Debian source stanza (same mirror, only the suite changes).
if [[ -f /etc/debian_version ]]; then
  if ! dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null | grep -q '^2[4-9]'; then
    if ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
      if [[ -f /etc/apt/sources.list.d/debian.sources ]]; then
        awk 'BEGIN{RS="";ORS="\n\n"} NR==1' /etc/apt/sources.list.d/debian.sources \
          | sed 's/^Suites:.*/Suites: bookworm-backports/' | $SUDO tee /etc/apt/sources.list.d/bookworm-backports.sources >/dev/null
      else
        mirror=$(awk '/^deb .*bookworm main/{print $2; exit}' /etc/apt/sources.list)
        echo "deb ${mirror} bookworm-backports main" | $SUDO tee /etc/apt/sources.list.d/bookworm-backports.list >/dev/null
      fi
    fi
    $SUDO apt-get update -qq
    $SUDO apt-get install -y -qq libusb-1.0-0 libgl1 libglib2.0-0 libegl1 libvulkan1 >/dev/null
    $SUDO apt-get install -y -qq -t bookworm-backports mesa-vulkan-drivers libegl-mesa0 libgl1-mesa-dri >/dev/null
  fi
fi

# --dev: headless Chromium, for the 3-D viewer's browser test (tests/viz/test_viewer.py screenshots the page).
if [[ -n "$extras" ]] && ! command -v chromium >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1; then
    $SUDO apt-get update -qq
    $SUDO apt-get install -y -qq chromium >/dev/null
  else
    echo "setup: no apt-get here; install Chromium for the viewer's browser test (it is skipped without it)" >&2
  fi
fi

python3 -c 'import sys; assert sys.version_info[:2] == (3, 11), "centerart needs Python 3.11"' 
[[ -x .venv/bin/python ]] || python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e ".${extras}"
.venv/bin/python -c "import centerart, sapien, pybullet, open3d, torch; print('centerart', centerart.__version__, 'ready')" 2>&1 | grep -v '^pybullet build time'
