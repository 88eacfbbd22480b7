#!/usr/bin/env bash
# Installs the Debian packages occ_improve builds against, and only those that are missing.
# Idempotent: a second run installs nothing. Exits non-zero with a clear message where it cannot.
set -euo pipefail

packages=(cmake g++ make pkg-config libeigen3-dev liboctomap-dev libpcl-dev libopenni2-dev
          libgtest-dev libbenchmark-dev zlib1g-dev libpng-dev libtiff-dev
          # Python bindings (python/): the module, its tests, the sample, and the wheel check's venv.
          python3-dev pybind11-dev python3-numpy python3-pytest python3-matplotlib python3-venv
          # occ_improve_live -view's headless test: a virtual X server (xvfb-run needs xauth).
          xvfb xauth)
# `install-deps.sh fuzz` (make fuzz) also installs clang, libFuzzer and the sanitizer runtimes it links.
if [ "${1:-}" = "fuzz" ]; then
  packages+=(clang libfuzzer-14-dev libclang-rt-14-dev)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
if [ "$(id -u)" -eq 0 ]; then
  sudo_cmd=()
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
  sudo_cmd=(sudo -n)
else
  echo "install-deps: missing packages (${missing[*]}) and no root or password-less sudo to install them." >&2
  echo "install-deps: run as root: apt-get install ${missing[*]}" >&2
  exit 1
fi
if ! command -v apt-get >/dev/null 2>&1; then
  echo "install-deps: apt-get not found; this script supports Debian 12. Install: ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq || { echo "install-deps: apt-get update failed" >&2; exit 1; }
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null \
  || { echo "install-deps: apt-get install failed for: ${missing[*]}" >&2; exit 1; }
echo "install-deps: installed ${#missing[@]} packages"
