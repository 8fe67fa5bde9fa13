#!/usr/bin/env bash
# Installs the Debian 12 packages PocketBot builds and tests with, and only those that are missing.
# Idempotent and fast (one dpkg-query) when everything is present; `apt-get update` runs only when
# something has to be installed. CI machines start fresh, so `make test` calls this first.
set -euo pipefail

PACKAGES=(
  # firmware: ATxmega128A3 build, cycle counts on simavr, WebAssembly build for the emulator
  gcc-avr avr-libc binutils-avr simavr
  clang lld libclang-rt-14-dev libclang-rt-14-dev-wasm32
  # the emulator's native engine and the benchmark's native reference: the same wasm turned into C (wasm2c)
  wabt
  # host tools: serial/pty plumbing, protocol generator, BlueZ D-Bus mock for the SDK tests
  socat python3 python3-dbusmock dbus make
  # the virtual Bluetooth controllers: Bumble in a venv of its own (scripts/ensure-bumble.sh)
  python3-venv
  # JVM build and the Kotlin/JS test run of sdk/core
  openjdk-17-jdk-headless maven nodejs
  # the control panel's headless UI tests draw text (Skia finds fonts through fontconfig)
  fontconfig fonts-dejavu-core
  # the Android app's APK without Gradle: resources and manifest, alignment, signing and its check
  aapt zipalign apksigner
  # fleets over MQTT: the broker the tests start (mosquitto_passwd comes with it), certificates for its TLS listener
  mosquitto openssl
)
# `ensure-deps.sh desktop`: what the control panel's window needs (a JRE with AWT, fonts); `screenshots` adds a
# virtual display to photograph it on.
case "${1:-}" in
  desktop) PACKAGES+=(openjdk-17-jre) ;;
  screenshots) PACKAGES+=(openjdk-17-jre xvfb xauth) ;;
esac

missing=()
# One dpkg-query for all packages; unknown packages print nothing and count as missing.
status=$(dpkg-query -W -f='${Package} ${Status}\n' "${PACKAGES[@]}" 2>/dev/null || true)
for pkg in "${PACKAGES[@]}"; do
  if ! grep -q "^${pkg} install ok installed$" <<<"$status"; then
    missing+=("$pkg")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "ensure-deps: installing ${missing[*]}"
if [ "$(id -u)" -eq 0 ]; then
  SUDO=()
elif command -v sudo >/dev/null 2>&1; then
  SUDO=(sudo)
else
  echo "ensure-deps: missing packages (${missing[*]}) and neither root nor sudo available" >&2
  exit 1
fi

# env inside sudo: sudo drops DEBIAN_FRONTEND otherwise. Recommends are skipped to keep a fresh
# CI machine's install short; every package the build needs is named above.
"${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
"${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
