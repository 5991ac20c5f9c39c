#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# systemd-analyze verify on deploy/rsud.service, with its install paths pointed at this build (verify
# checks that ExecStart's program exists). Usage: verify_unit.sh UNIT_TEMPLATE RSUD_DIR CONFIG_DIR WORK_DIR
set -eu
template=$1 rsud_dir=$2 config_dir=$3 work=$4
if ! command -v systemd-analyze >/dev/null 2>&1; then
  echo "SKIP: systemd-analyze is not installed (apt-get install systemd)"
  exit 77
fi
mkdir -p "$work"
sed -e "s#@CMAKE_INSTALL_FULL_SBINDIR@#$rsud_dir#g" \
    -e "s#@CMAKE_INSTALL_FULL_SYSCONFDIR@/rsud#$config_dir#g" "$template" > "$work/rsud.service"
if grep -q '@[A-Z_]*@' "$work/rsud.service"; then
  echo "FAIL: unsubstituted @VARIABLE@ left in the unit"; exit 1
fi
out=$(systemd-analyze verify "$work/rsud.service" 2>&1) || { echo "$out"; echo "FAIL: systemd-analyze verify"; exit 1; }
# verify exits 0 on some problems it only warns about: treat any output about the unit as a failure.
if printf '%s' "$out" | grep -q 'rsud.service'; then
  echo "$out"; echo "FAIL: systemd-analyze verify reported problems"; exit 1
fi
# systemd's own rating of the sandbox (offline: the unit file alone); 0 is the best, 10 the worst.
# 1.4 today; above 2 means a protection was lost.
security=$(systemd-analyze security --offline=true "$work/rsud.service" 2>&1) || { echo "$security"; echo "FAIL: systemd-analyze security"; exit 1; }
exposure=$(printf '%s\n' "$security" | sed -n 's/.*Overall exposure level for rsud.service: \([0-9.]*\).*/\1/p')
[ -n "$exposure" ] || { echo "$security"; echo "FAIL: no exposure level"; exit 1; }
if ! awk -v e="$exposure" 'BEGIN { exit !(e <= 2.0) }'; then
  printf '%s\n' "$security" | grep '✗'; echo "FAIL: exposure level $exposure > 2.0"; exit 1
fi
echo "systemd-analyze security --offline=true: exposure level $exposure"
# The hardening the issue asks for is really there.
for key in Type=notify DynamicUser=yes ProtectSystem=strict ProtectHome=yes PrivateTmp=yes NoNewPrivileges=yes \
           'RestrictAddressFamilies=AF_INET AF_INET6 AF_UNIX' 'CapabilityBoundingSet=$' 'SystemCallFilter=@system-service' \
           WatchdogSec= Restart=on-failure 'ExecReload=/bin/kill -HUP $MAINPID' \
           'LoadCredential=rsu.key:' 'ExecStart=.* --key %d/rsu.key$'; do
  grep -q "^$key" "$work/rsud.service" || { echo "FAIL: the unit lacks $key"; exit 1; }
done
echo "OK: $work/rsud.service verified"
