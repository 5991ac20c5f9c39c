#!/bin/sh
# rsud --check-config accepts the shipped configuration and refuses broken ones with an error that
# names the file, the line and the field. Usage: check_config.sh RSUD CONFIG WORK_DIR
set -u
rsud=$1 config=$2 work=$3
mkdir -p "$work"
"$rsud" --check-config --config "$config" || { echo "FAIL: the shipped configuration is refused"; exit 1; }

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
printf 'rsu_id: 1\nlidar: [1, 2\n' > "$work/syntax.yaml"
expect_refused syntax "syntax.yaml:"
echo "OK"
