#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# rsud --check-config accepts the shipped configuration and refuses broken ones with an error that
# names the file, the line and the field. The shipped file's keys (/etc/rsud/keys/...) are made here by
# rsu-keygen and the paths pointed at them. Usage: check_config.sh RSUD CONFIG WORK_DIR RSU_KEYGEN
set -u
rsud=$1 shipped=$2 work=$3 keygen=$4
rm -rf "$work" && mkdir -p "$work/keys"
"$keygen" "$work/keys/rsu" >/dev/null || { echo "FAIL: rsu-keygen"; exit 1; }
"$keygen" "$work/keys/car" --trust-list "$work/keys/trust.list" --role vehicle --ids 7 >/dev/null || exit 1
# Under a strict umask the folders, public key and trust list rsu-keygen makes stay readable by rsud's
# own user (the unit's DynamicUser=); the secret key alone is 0600.
(umask 077 && "$keygen" "$work/strict/keys/rsu" --trust-list "$work/strict/keys/trust.list" --role rsu --ids 1 \
  >/dev/null) || { echo "FAIL: rsu-keygen under umask 077"; exit 1; }
for f in strict:755 strict/keys:755 strict/keys/rsu.pub:644 strict/keys/trust.list:644 strict/keys/rsu.key:600; do
  mode=$(stat -c %a "$work/${f%:*}")
  [ "$mode" = "${f#*:}" ] || { echo "FAIL: umask 077: $work/${f%:*} is mode $mode, expected ${f#*:}"; exit 1; }
done
# rsu-keygen: the secret key is mode 0600; nothing is overwritten without --force; a key is listed once.
[ "$(stat -c %a "$work/keys/rsu.key")" = 600 ] || { echo "FAIL: rsu.key is not mode 0600"; exit 1; }
before=$(cat "$work/keys/rsu.key")
if out=$("$keygen" "$work/keys/rsu" 2>&1); then echo "FAIL: rsu-keygen overwrote a key"; exit 1; fi
case "$out" in *"exists; not overwritten (use --force)"*) ;; *) echo "FAIL: keygen said: $out"; exit 1 ;; esac
[ "$before" = "$(cat "$work/keys/rsu.key")" ] || { echo "FAIL: the refused run changed rsu.key"; exit 1; }
"$keygen" "$work/keys/spare" >/dev/null && "$keygen" "$work/keys/spare" --force >/dev/null || exit 1
if out=$("$keygen" --public-key "$work/keys/car.pub" --trust-list "$work/keys/trust.list" --role vehicle \
         --ids 8 2>&1); then echo "FAIL: a key was listed twice"; exit 1; fi
case "$out" in *"is listed twice"*) ;; *) echo "FAIL: keygen said: $out"; exit 1 ;; esac
config=$work/rsud.yaml
sed "s|/etc/rsud/keys/|$work/keys/|" "$shipped" > "$config"
out=$("$rsud" --check-config --config "$config") || { echo "FAIL: the shipped configuration is refused"; exit 1; }
case "$out" in *"security signed: key "*"1 vehicle key(s)"*) ;; *) echo "FAIL: no security summary in: $out"; exit 1 ;; esac
case "$out" in *"readable by group"*) echo "FAIL: rsu-keygen's key reported readable: $out"; exit 1 ;; esac
case "$out" in *"announcements verified within 100 m of the LiDAR (coverage + 50 m)"*) ;;
  *) echo "FAIL: no verification radius in: $out"; exit 1 ;; esac
sed 's/^  verify_beyond_coverage_m: 50 /  verify_beyond_coverage_m: all /' "$config" > "$work/verify_all.yaml"
out=$("$rsud" --check-config --config "$work/verify_all.yaml") || { echo "FAIL: verify all refused"; exit 1; }
case "$out" in *"every announcement verified"*) ;; *) echo "FAIL: verify all not reported: $out"; exit 1 ;; esac
# A secret key others can read is reported.
cp "$work/keys/rsu.key" "$work/keys/open.key" && chmod 644 "$work/keys/open.key"
sed "s|$work/keys/rsu.key|$work/keys/open.key|" "$config" > "$work/open_key.yaml"
out=$("$rsud" --check-config --config "$work/open_key.yaml") || { echo "FAIL: open_key refused"; exit 1; }
case "$out" in *"WARNING: readable by group or others"*) ;; *) echo "FAIL: no warning in: $out"; exit 1 ;; esac

expect_refused() {  # NAME EXPECTED_TEXT: the file $work/NAME.yaml must be refused with EXPECTED_TEXT
  out=$("$rsud" --check-config --config "$work/$1.yaml" 2>&1); rc=$?
  if [ $rc -ne 1 ]; then echo "FAIL: $1: exit code $rc, expected 1"; echo "$out"; exit 1; fi
  case "$out" in *"$2"*) ;; *) echo "FAIL: $1: expected \"$2\" in: $out"; exit 1 ;; esac
  echo "ok: $1 refused: $out"
}
sed 's/^    z: 2.0$/    z: two/' "$config" > "$work/bad_number.yaml"
expect_refused bad_number "bad_number.yaml:$(grep -n '^    z: 2.0$' "$config" | cut -d: -f1): lidar.mount.z: expected a number"
sed 's/^  model: vlp32c/  model: vlp99/' "$config" > "$work/bad_model.yaml"
expect_refused bad_model "lidar.model: unknown LiDAR model"
sed 's/^  capacity: 256/  capacitty: 256/' "$config" > "$work/typo.yaml"
expect_refused typo "registry.capacitty: unknown field"
sed 's/^  port: 4500/  port: 70000/' "$config" > "$work/bad_port.yaml"
expect_refused bad_port "v2i.port: must be a port number"
sed 's/^  verify_beyond_coverage_m: 50 /  verify_beyond_coverage_m: -5 /' "$config" > "$work/bad_margin.yaml"
expect_refused bad_margin "security.verify_beyond_coverage_m: expected a margin in metres (>= 0) or \"all\", got \"-5\""
printf 'rsu_id: 1\nlidar: [1, 2\n' > "$work/syntax.yaml"
expect_refused syntax "syntax.yaml:"
# Security: a missing key file, a malformed key, a malformed trust list, no security section at all.
sed "s|$work/keys/rsu.key|$work/keys/missing.key|" "$config" > "$work/no_key.yaml"
expect_refused no_key "security.key_file: $work/keys/missing.key"
printf 'ed25519-secret-key 12345\n' > "$work/keys/short.key"
sed "s|$work/keys/rsu.key|$work/keys/short.key|" "$config" > "$work/short_key.yaml"
expect_refused short_key "short.key:1: key must be exactly 64 hex digits"
{ cat "$work/keys/trust.list"; echo "vehicle 00 7"; } > "$work/keys/bad.list"
sed "s|$work/keys/trust.list|$work/keys/bad.list|" "$config" > "$work/bad_list.yaml"
expect_refused bad_list "bad.list:3: public key must be exactly 64 hex digits"
sed '/^security:/,/^$/d' "$config" > "$work/no_security.yaml"  # signed by default, keys in /etc/rsud/keys
if [ ! -e /etc/rsud/keys/rsu.key ]; then
  expect_refused no_security "security.key_file: /etc/rsud/keys/rsu.key"
fi
# An Ouster: lidar.model with the sensor's metadata JSON; the UDP port is the metadata's unless set.
metadata=$(dirname "$shipped")/../tests/data/real/ouster/OS-1-128_v2.3.0_1024x10.json
cp "$metadata" "$work/os1_128.json"
sed -e "s|^  model: vlp32c.*|  model: os1-128\n  metadata: os1_128.json|" \
    -e '/^      port: 2368/d' "$config" > "$work/ouster.yaml"
out=$("$rsud" --check-config --config "$work/ouster.yaml") || { echo "FAIL: the Ouster configuration is refused"; "$rsud" --check-config --config "$work/ouster.yaml"; exit 1; }
case "$out" in *"lidar os1-128"*"lidar metadata $work/os1_128.json"*"input udp 0.0.0.0:the metadata's udp_port_lidar"*) ;;
  *) echo "FAIL: Ouster summary: $out"; exit 1 ;; esac
sed 's/^  model: os1-128/  model: os1-64/' "$work/ouster.yaml" > "$work/ouster_other_model.yaml"
expect_refused ouster_other_model "LiDAR model os1-64, but $work/os1_128.json describes an os1-128"
sed '/^  metadata: /d' "$work/ouster.yaml" > "$work/ouster_no_metadata.yaml"
expect_refused ouster_no_metadata "lidar.model: an Ouster needs lidar.metadata"
sed 's/^  metadata: os1_128.json/  metadata: missing.json/' "$work/ouster.yaml" > "$work/ouster_missing.yaml"
expect_refused ouster_missing "lidar.metadata: $work/missing.json:0: <file>: cannot open"
sed 's/"lidar_mode": "1024x10"/"lidar_mode": "1024x15"/' "$work/os1_128.json" > "$work/os1_128_broken.json"
sed 's/^  metadata: os1_128.json/  metadata: os1_128_broken.json/' "$work/ouster.yaml" > "$work/ouster_broken.yaml"
expect_refused ouster_broken "os1_128_broken.json:$(grep -n '"lidar_mode"' "$work/os1_128.json" | cut -d: -f1): lidar_mode: unknown lidar_mode \"1024x15\""
sed "s|^  model: vlp32c.*|  model: vlp32c\n  metadata: os1_128.json|" "$config" > "$work/velodyne_metadata.yaml"
expect_refused velodyne_metadata "lidar.metadata: the metadata JSON is for Ouster sensors"
echo "OK"
