#!/usr/bin/env bash
# Installs the Debian 12 packages flowplan builds and runs with; installs only
# what is missing, with sudo when not root. With --fuzz, also Clang with
# libFuzzer for the fuzz targets (`make fuzz`).
set -euo pipefail

packages=(
  build-essential cmake ninja-build git
  libtorch-dev libopenblas0-openmp
  libmujoco-dev libhdf5-dev libspdlog-dev libcli11-dev libeigen3-dev libyaml-cpp-dev
  libgtest-dev libgmock-dev libbenchmark-dev libgloo-dev libosmesa6-dev zlib1g-dev liburdfdom-dev
  python3 python3-dev pybind11-dev python3-torch python3-h5py python3-numpy python3-matplotlib python3-yaml python3-pil
  python3-pytest
)
if [ "${1:-}" = "--fuzz" ]; then
  packages+=(clang libclang-rt-14-dev)  # libFuzzer and the sanitizer runtimes: only a Recommends of clang
fi

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  sudo="sudo"
fi
echo "installing: ${missing[*]}"
$sudo apt-get update
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
