#!/usr/bin/env bash
# Runs every test of the workspace on a fresh Debian machine: installs what is missing
# (Debian packages, the pinned Python venv of the test peers), then runs the tests.
# Usage: scripts/test.sh [extra cargo test args]
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

# 1. Debian packages the tests use as independent peers or renderers.
apt_packages=()
need() { dpkg -s "$1" >/dev/null 2>&1 || apt_packages+=("$1"); }
need python3-venv
need mbpoll
# console snapshots (egui_kittest renders with wgpu on Mesa lavapipe) and docs screenshots
need mesa-vulkan-drivers
need libgl1-mesa-dri
need xvfb
need imagemagick
# a real console window found by name (tests/integration/cli.rs)
need x11-utils
need spin
if [ ${#apt_packages[@]} -gt 0 ]; then
  echo "scripts/test.sh: installing Debian packages: ${apt_packages[*]}"
  if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${apt_packages[@]}" >/dev/null
fi

# 2. The pinned Python venv (test peers such as blark and pymodbus).
venv="${VIGIE_VENV:-$root/.venv}"
if [ -s requirements-test.txt ]; then
  stamp="$venv/.requirements-test.txt"
  if [ ! -x "$venv/bin/python" ] || ! cmp -s requirements-test.txt "$stamp"; then
    echo "scripts/test.sh: creating the test venv in $venv"
    python3 -m venv "$venv"
    "$venv/bin/pip" install -q --disable-pip-version-check -r requirements-test.txt
    cp requirements-test.txt "$stamp"
  fi
fi
export VIGIE_VENV="$venv"

# 3. The style, then the tests, then the lints and the documentation; each check
#    runs even when an earlier one failed, and the script fails if any did.
status=0
echo "scripts/test.sh: cargo fmt --check"
cargo fmt --all -- --check || status=1
cargo test --workspace --locked --no-fail-fast "$@" || status=1
echo "scripts/test.sh: cargo clippy (warnings denied)"
cargo clippy --workspace --all-targets --locked -- -D warnings || status=1
echo "scripts/test.sh: cargo doc (warnings denied)"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --locked || status=1
exit $status
