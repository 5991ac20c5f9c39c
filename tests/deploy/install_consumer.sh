#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# cmake --install into a fresh prefix installs every program, the unit, the example configuration, the
# sysctl snippet and the vehicle client package; a program outside the project is then built against the
# package twice, with find_package(RsuVehicleClient) and with pkg-config, and run.
# Usage: install_consumer.sh BUILD_DIR CONSUMER_SOURCE_DIR WORK_DIR [CONSUMER_FLAGS]
# CONSUMER_FLAGS: compiler and linker flags the consumer needs to load the installed library (a sanitizer
# build's -fsanitize=...); empty for a Release build.
set -eu
build=$1 consumer=$2 work=$3 flags=${4:-}
rm -rf "$work" && mkdir -p "$work"
prefix=$work/prefix
cmake --install "$build" --prefix "$prefix" >"$work/install.log" || { cat "$work/install.log"; echo "FAIL: install"; exit 1; }
for f in sbin/rsud bin/rsu-keygen bin/rsu-vehicle bin/rsu-sim bin/rsu-decode bin/rsu-relay bin/rsu-vehicle-replay \
         bin/rsu-pilot bin/rsu-corridor bin/rsu-calibrate lib/systemd/system/rsud.service etc/rsud/rsud.yaml \
         lib/sysctl.d/60-rsud.conf include/rsu/vehicle_client/vehicle_client.h include/rsu/v2i/security/key_text.h \
         lib/cmake/RsuVehicleClient/RsuVehicleClientConfig.cmake lib/pkgconfig/rsu-vehicle-client.pc; do
  [ -e "$prefix/$f" ] || { echo "FAIL: $f not installed"; ls -R "$prefix"; exit 1; }
done
for p in "$prefix"/bin/* "$prefix"/sbin/*; do  # every installed program runs
  "$p" --help >/dev/null 2>&1 || { echo "FAIL: $p --help"; exit 1; }
done
# The shared library with its SOVERSION: the real file, the soname link, the development link.
so=$(readlink "$prefix/lib/librsu-vehicle-client.so")
soname=$(objdump -p "$prefix/lib/$so" | awk '/SONAME/ {print $2}')
[ "$soname" = librsu-vehicle-client.so.0 ] || { echo "FAIL: SONAME '$soname'"; exit 1; }
[ -e "$prefix/lib/$soname" ] || { echo "FAIL: no $soname"; exit 1; }
"$prefix/bin/rsu-keygen" "$work/car" >"$work/keygen.out"
id=$(sed -n 's/^key id \([0-9a-f]*\):.*/\1/p' "$work/keygen.out")
[ -n "$id" ] || { cat "$work/keygen.out"; echo "FAIL: no key id from rsu-keygen"; exit 1; }
expected="key id $id, rsu 127.0.0.1:4500"

cmake -S "$consumer" -B "$work/with_cmake" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_CXX_FLAGS="$flags" >"$work/cmake.log" 2>&1 &&
  cmake --build "$work/with_cmake" >>"$work/cmake.log" 2>&1 || { cat "$work/cmake.log"; echo "FAIL: find_package build"; exit 1; }
out=$(LD_LIBRARY_PATH="$prefix/lib" "$work/with_cmake/consumer" "$work/car.key" 127.0.0.1:4500)
case "$out" in *"$expected"*) echo "ok: find_package(RsuVehicleClient): $out" ;; *) echo "FAIL: $out"; exit 1 ;; esac

export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
# shellcheck disable=SC2046,SC2086
c++ -std=c++20 $flags -o "$work/with_pkg_config" "$consumer/consumer.cpp" $(pkg-config --cflags --libs rsu-vehicle-client) ||
  { echo "FAIL: pkg-config build"; exit 1; }
out=$(LD_LIBRARY_PATH="$prefix/lib" "$work/with_pkg_config" "$work/car.key" 127.0.0.1:4500)
case "$out" in *"$expected"*) echo "ok: pkg-config rsu-vehicle-client: $out" ;; *) echo "FAIL: $out"; exit 1 ;; esac
echo OK
