#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs every build, test and figure dependency from Debian packages. Idempotent: packages
# already present are skipped, so a second run costs one dpkg query.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git clang-format
  libgtest-dev libgmock-dev libbenchmark-dev
  libeigen3-dev libpcl-dev libembree-dev
  libboost-dev libboost-system-dev libboost-program-options-dev
  libspdlog-dev libfmt-dev protobuf-compiler libprotobuf-dev
  libyaml-cpp-dev libsystemd-dev libpng-dev libsodium-dev
  libssl-dev  # tests: MD5, to compare Ouster range images with the Ouster SDK's digests
  cyclonedds-dev cyclonedds-tools
  clang libclang-rt-14-dev  # build-asan/ and fuzz/: clang recommends, not depends on, the libFuzzer runtime
  systemd
  python3 python3-numpy python3-matplotlib python3-yaml
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

if [ "$(id -u)" -ne 0 ]; then SUDO=sudo; else SUDO=; fi
echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
