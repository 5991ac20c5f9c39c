#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# The Debian packages (cmake/packaging.cmake) built from this build tree with cpack, installed with dpkg
# into a scratch root (never into this machine: dpkg --root, with this machine's package database copied
# in so that every Depends: is checked against what is really installed here), then: the packages are
# installed and configured, their files are where the unit and the docs say, the configuration files are
# conffiles, the installed unit names the installed rsud, the installed programs run (--version), the
# installed rsud accepts the installed configuration with keys made by the installed rsu-keygen, and a
# program's includes resolve through the -dev package's pkg-config file; then all are purged.
# Usage: package_smoke.sh BUILD_DIR WORK_DIR VERSION CONSUMER_SOURCE
set -eu
build=$1 work=$2 version=$3 consumer=$4
fail() { echo "FAIL: $*"; exit 1; }
for tool in cpack dpkg dpkg-deb dpkg-query dpkg-shlibdeps; do
  command -v "$tool" >/dev/null 2>&1 || { echo "SKIP: $tool is not installed (Debian: apt-get install dpkg-dev)"; exit 77; }
done
rm -rf "$work" && mkdir -p "$work"
cpack --config "$build/CPackConfig.cmake" -B "$work/packages" >"$work/cpack.log" 2>&1 || { cat "$work/cpack.log"; fail "cpack"; }
packages="rsud rsu-tools librsu-vehicle-client0 librsu-vehicle-client-dev"
for p in $packages; do
  [ -f "$work/packages/${p}_${version}_$(dpkg --print-architecture).deb" ] || { ls "$work/packages"; fail "no package $p"; }
done

root=$work/root
mkdir -p "$root/var/lib/dpkg/info" "$root/var/lib/dpkg/updates" "$root/var/log"
cp /var/lib/dpkg/status "$root/var/lib/dpkg/status"
# Their file lists, empty (dpkg warns about each one missing).
dpkg-query -W -f='${binary:Package}\n' | while read -r p; do : >"$root/var/lib/dpkg/info/$p.list"; done
as_user=""
[ "$(id -u)" = 0 ] || as_user=--force-not-root
# Maintainer scripts run outside the root with DPKG_ROOT set (they then leave the machine alone).
# shellcheck disable=SC2086
dpkg --root="$root" --log=/dev/null --force-script-chrootless $as_user -i "$work"/packages/*.deb >"$work/dpkg.log" 2>&1 ||
  { cat "$work/dpkg.log"; fail "dpkg -i"; }
for p in $packages; do
  status=$(dpkg-query --root="$root" -W -f='${Status} ${Version}' "$p")
  [ "$status" = "install ok installed $version" ] || fail "$p: '$status'"
done
for f in usr/sbin/rsud usr/lib/systemd/system/rsud.service etc/rsud/rsud.yaml etc/rsud/cyclonedds-loopback.xml \
         usr/lib/sysctl.d/60-rsud.conf usr/bin/rsu-keygen usr/bin/rsu-vehicle usr/bin/rsu-sim usr/bin/rsu-calibrate usr/bin/rsu-autoware-sidecar \
         usr/lib/librsu-vehicle-client.so.0 usr/lib/librsu-vehicle-client.so include/rsu/vehicle_client/vehicle_client.h \
         usr/lib/cmake/RsuVehicleClient/RsuVehicleClientConfig.cmake usr/lib/pkgconfig/rsu-vehicle-client.pc \
         usr/share/man/man8/rsud.8 usr/share/man/man1/rsu-autoware-sidecar.1 usr/share/man/man1/rsu-sim.1; do
  case $f in include/*) f=usr/$f ;; esac
  [ -e "$root/$f" ] || fail "/$f not installed"
done
conffiles=$(dpkg-query --root="$root" -W -f='${Conffiles}' rsud)
for f in /etc/rsud/rsud.yaml /etc/rsud/cyclonedds-loopback.xml; do
  case "$conffiles" in *"$f "*) ;; *) fail "$f is not a conffile of rsud: $conffiles" ;; esac
done
unit=$root/usr/lib/systemd/system/rsud.service
grep -q '^ExecStart=/usr/sbin/rsud --config /etc/rsud/rsud.yaml --key %d/rsu.key$' "$unit" || { grep Exec "$unit"; fail "ExecStart"; }
grep -q '^LoadCredential=rsu.key:/etc/rsud/keys/rsu.key$' "$unit" || fail "LoadCredential"
for p in "$root"/usr/sbin/rsud "$root"/usr/bin/*; do
  out=$("$p" --version 2>&1) || fail "$p --version: $out"
  case "$out" in *"$version"*) ;; *) fail "$p --version says '$out'" ;; esac
done
# The installed rsud with the installed configuration, its keys where the unit expects them made by the
# installed rsu-keygen (here under the scratch root).
keys=$root/etc/rsud/keys
"$root/usr/bin/rsu-keygen" "$keys/rsu" >/dev/null || fail "rsu-keygen"
"$root/usr/bin/rsu-keygen" "$keys/car" --trust-list "$keys/trust.list" --role vehicle --ids 7 >/dev/null || fail "rsu-keygen"
sed "s|/etc/rsud/keys/|$keys/|" "$root/etc/rsud/rsud.yaml" >"$work/rsud.yaml"
out=$("$root/usr/sbin/rsud" --check-config --config "$work/rsud.yaml" 2>&1) || { echo "$out"; fail "rsud --check-config"; }
case "$out" in *"security signed: key "*) ;; *) fail "no security summary in: $out" ;; esac
# The -dev package's headers are complete: a program's includes resolve through pkg-config alone (a full
# build and run of that program against the installed package: deploy_install_and_consume). The
# development link leads to the library with its SONAME.
# shellcheck disable=SC2046
c++ -std=c++20 -E -o /dev/null "$consumer/consumer.cpp" \
  $(PKG_CONFIG_PATH="$root/usr/lib/pkgconfig" pkg-config --cflags rsu-vehicle-client) || fail "the consumer's includes"
soname=$(objdump -p "$(readlink -f "$root/usr/lib/librsu-vehicle-client.so")" | awk '/SONAME/ {print $2}')
[ "$soname" = librsu-vehicle-client.so.0 ] || fail "SONAME '$soname'"
# Removal: purge takes the files and the conffiles (the keys made above are the operator's and stay).
# shellcheck disable=SC2086
dpkg --root="$root" --log=/dev/null --force-script-chrootless $as_user --purge $packages >"$work/purge.log" 2>&1 ||
  { cat "$work/purge.log"; fail "dpkg --purge"; }
for f in usr/sbin/rsud etc/rsud/rsud.yaml usr/lib/librsu-vehicle-client.so.0 usr/bin/rsu-keygen; do
  [ ! -e "$root/$f" ] || fail "/$f left after purge"
done
echo "OK: $(ls "$work/packages"/*.deb | wc -l) packages installed into $root and checked"
