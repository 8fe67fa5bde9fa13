#!/usr/bin/env bash
# Builds the PocketBot APK without Gradle (Maven calls this; see pom.xml):
#
#   apk.sh resources                      aapt2: res/ and the manifest -> $BUILD_DIR/resources.ap_ (+ R8 keep rules)
#   apk.sh package CLASSES CLASSPATH      R8 -> dex, the APK, zipalign, a debug signature, then its checks
#
# Environment (set by the pom): ANDROID_JAR (android-all of API 34: the platform to link and compile against),
# R8_JAR, BUILD_DIR, JAVA, VERSION_NAME. The output is $BUILD_DIR/pocketbot.apk.
set -euo pipefail

HERE="$(cd "$(dirname "$0")" && pwd)"
MIN_SDK=26
TARGET_SDK=34
PACKAGE=org.pocketbot.android
APK="$BUILD_DIR/pocketbot.apk"
# R8 on C1 only: it runs once per build, so C2's warm-up never pays off (about 2x faster on 2 cores).
R8=("$JAVA" -XX:TieredStopAtLevel=1 -XX:+UseParallelGC -Xmx2g -cp "$R8_JAR")

fail() { echo "apk.sh: $*" >&2; exit 1; }

resources() {
  mkdir -p "$BUILD_DIR"
  aapt2 compile --dir "$HERE/src/main/res" -o "$BUILD_DIR/res.zip"
  aapt2 link -o "$BUILD_DIR/resources.ap_" -I "$ANDROID_JAR" \
    --manifest "$HERE/src/main/AndroidManifest.xml" \
    --min-sdk-version "$MIN_SDK" --target-sdk-version "$TARGET_SDK" \
    --version-code 1 --version-name "$VERSION_NAME" \
    --proguard "$BUILD_DIR/aapt-rules.pro" \
    "$BUILD_DIR/res.zip" 2> >(grep -v "Unknown chunk type" >&2) # Debian's aapt2 (Android 10) skips API 34 chunks it need not read
}

package() {
  local classes="$1" classpath="$2"
  local started=$SECONDS
  [ -f "$BUILD_DIR/resources.ap_" ] || fail "no resources.ap_: run 'apk.sh resources' first"
  local inputs=() entries=()
  IFS=':' read -r -a entries <<<"$classpath"
  # R8 reads jars, not folders: the app's classes go in as one.
  "${JAVA%/java}/jar" cf "$BUILD_DIR/app-classes.jar" -C "$classes" .
  inputs+=("$BUILD_DIR/app-classes.jar")
  for entry in "${entries[@]}"; do [ "$entry" = "$classes" ] || inputs+=("$entry"); done

  # Dex: R8 keeps what the manifest names (aapt2's rules) and what that reaches, and drops the rest (the SDK's
  # serial and BlueZ transports, unused library code). No renaming or optimisation: the dex is the tested code.
  rm -rf "$BUILD_DIR/dex" && mkdir -p "$BUILD_DIR/dex"
  "${R8[@]}" com.android.tools.r8.R8 --release --min-api "$MIN_SDK" \
    --lib "$ANDROID_JAR" --lib "${JAVA%/bin/java}" \
    --pg-conf "$BUILD_DIR/aapt-rules.pro" --pg-conf "$HERE/proguard-rules.pro" \
    --output "$BUILD_DIR/dex" "${inputs[@]}" \
    2> >(grep -v "^Warning: Resource '.*' already exists" >&2) # the libraries' klib metadata, not used in the APK

  # META-INF/services of the libraries (coroutines finds Dispatchers.Main through them); R8 keeps no resources.
  rm -rf "$BUILD_DIR/meta" && mkdir -p "$BUILD_DIR/meta"
  for jar in "${inputs[@]}"; do
    [ -f "$jar" ] || continue
    (cd "$BUILD_DIR/meta" && "${JAVA%/java}/jar" xf "$jar" META-INF/services)
  done

  local unsigned="$BUILD_DIR/unsigned.apk" aligned="$BUILD_DIR/aligned.apk"
  cp "$BUILD_DIR/resources.ap_" "$unsigned"
  (cd "$BUILD_DIR/dex" && aapt add "$unsigned" classes*.dex >/dev/null)
  if [ -d "$BUILD_DIR/meta/META-INF/services" ]; then
    (cd "$BUILD_DIR/meta" && aapt add "$unsigned" META-INF/services/* >/dev/null)
  fi
  zipalign -p -f 4 "$unsigned" "$aligned"

  # A debug key made here, for this checkout (never committed): reinstalling over an APK signed with another key
  # needs `adb uninstall org.pocketbot.android` first.
  local keystore="$BUILD_DIR/debug.keystore"
  if [ ! -f "$keystore" ]; then
    keytool -genkeypair -keystore "$keystore" -storepass android -keypass android -alias androiddebugkey \
      -keyalg RSA -keysize 2048 -validity 10000 -dname "CN=PocketBot Debug,O=PocketBot,C=US" >/dev/null 2>&1 \
      || fail "keytool could not make the debug key"
  fi
  apksigner sign --ks "$keystore" --ks-pass pass:android --key-pass pass:android --ks-key-alias androiddebugkey \
    --out "$APK" "$aligned"
  rm -f "$unsigned" "$aligned" "$APK.idsig"

  check
  echo "apk.sh: $APK: $(stat -c %s "$APK") bytes, $(method_count) dex methods, built in $((SECONDS - started)) s"
}

# The APK checks itself: a valid signature, the manifest as meant, and only the platform API it is allowed to use.
check() {
  apksigner verify --verbose "$APK" >"$BUILD_DIR/apksigner.txt" || fail "apksigner verify failed: $(cat "$BUILD_DIR/apksigner.txt")"
  grep -q "Verified using v2 scheme (APK Signature Scheme v2): true" "$BUILD_DIR/apksigner.txt" \
    || fail "not signed with APK Signature Scheme v2: $(cat "$BUILD_DIR/apksigner.txt")"

  aapt2 dump badging "$APK" >"$BUILD_DIR/badging.txt" 2>&1 || fail "aapt2 dump badging failed: $(cat "$BUILD_DIR/badging.txt")"
  local want=(
    "package: name='$PACKAGE'"
    "sdkVersion:'$MIN_SDK'"
    "targetSdkVersion:'$TARGET_SDK'"
    "uses-permission: name='android.permission.BLUETOOTH_SCAN'"
    "uses-permission: name='android.permission.BLUETOOTH_CONNECT'"
    "uses-permission: name='android.permission.BLUETOOTH' maxSdkVersion='30'"
    "uses-permission: name='android.permission.BLUETOOTH_ADMIN' maxSdkVersion='30'"
    "uses-permission: name='android.permission.ACCESS_FINE_LOCATION' maxSdkVersion='30'"
    "uses-permission: name='android.permission.INTERNET'"
    "uses-permission: name='android.permission.FOREGROUND_SERVICE_CONNECTED_DEVICE'"
    "launchable-activity: name='$PACKAGE.MainActivity'"
  )
  for line in "${want[@]}"; do
    grep -qF "$line" "$BUILD_DIR/badging.txt" || fail "aapt2 dump badging lacks \"$line\":
$(cat "$BUILD_DIR/badging.txt")"
  done

  # Every class, method and field the dex uses exists: in Android 14's android-all (android.*) or the JDK (java.*:
  # android-all leaves those to the JVM Robolectric runs on). A library the APK lacks fails here ...
  local jdk="${JAVA%/bin/java}"
  "${R8[@]}" com.android.tools.r8.tracereferences.TraceReferences --check --lib "$ANDROID_JAR" --lib "$jdk" \
    --source "$APK" >"$BUILD_DIR/missing.txt" 2>&1 || fail "the APK uses classes or members that do not exist:
$(cat "$BUILD_DIR/missing.txt")"
  # ... and the platform API it uses is exactly the reviewed public API in api/platform-api.txt: the android.* members
  # (keep rules on android-all), and the java.* ones (what is missing without the JDK), which Android's libcore must have.
  "${R8[@]}" com.android.tools.r8.tracereferences.TraceReferences --keep-rules --lib "$ANDROID_JAR" --lib "$jdk" \
    --source "$APK" --target "$ANDROID_JAR" --output "$BUILD_DIR/android-used.txt"
  "${R8[@]}" com.android.tools.r8.tracereferences.TraceReferences --check --lib "$ANDROID_JAR" --source "$APK" \
    >"$BUILD_DIR/java-used.txt" 2>&1 || true
  { grep -v '^#' "$BUILD_DIR/android-used.txt"
    sed -n 's/^Missing \(class\|method\|field\) \(.*\) (referenced from.*/\1 \2/p' "$BUILD_DIR/java-used.txt" | LC_ALL=C sort -u
  } >"$BUILD_DIR/platform-api-used.txt"
  if ! diff -u "$HERE/api/platform-api.txt" "$BUILD_DIR/platform-api-used.txt" \
      >"$BUILD_DIR/platform-api.diff"; then
    if [ "${POCKETBOT_API_UPDATE:-}" = 1 ]; then
      cp "$BUILD_DIR/platform-api-used.txt" "$HERE/api/platform-api.txt"
      echo "apk.sh: api/platform-api.txt updated: review every new line against the public SDK reference"
    else
      fail "the platform API the app uses changed (+ new, - no longer used). Check each new line against the public
SDK reference (developer.android.com: public, and present at minSdk $MIN_SDK or guarded by a version check), then
update the list with POCKETBOT_API_UPDATE=1 make apk:
$(cat "$BUILD_DIR/platform-api.diff")"
    fi
  fi
}

# Method references of all dex files (the 64K limit counts these): method_ids_size at offset 88 of each header.
method_count() {
  local total=0 n
  for dex in "$BUILD_DIR"/dex/classes*.dex; do
    n=$(od -An -t u4 -j 88 -N 4 "$dex" | tr -d ' ')
    total=$((total + n))
  done
  echo "$total"
}

case "${1:-}" in
  resources) resources ;;
  package) shift; package "$@" ;;
  *) fail "usage: apk.sh resources | package CLASSES CLASSPATH" ;;
esac
