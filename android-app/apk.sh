#!/usr/bin/env bash
# Builds the PocketBot APK without Gradle (Maven calls this; see pom.xml):
#
#   apk.sh resources                      aapt2: res/ and the manifest (merged: + uses-sdk) -> $BUILD_DIR/resources.ap_
#   apk.sh package CLASSES CLASSPATH      R8 -> dex, the APK, zipalign, a debug signature, then its checks
#
# Environment (set by the pom): ANDROID_JAR (android-all of API 35: the platform to link and compile against),
# R8_JAR, BUILD_DIR, JAVA, VERSION_NAME (the project version). The output is $BUILD_DIR/pocketbot.apk.
#
# Signing (android-app/README.md): with POCKETBOT_KEYSTORE set, the release key in it (POCKETBOT_KEY_ALIAS,
# passwords in POCKETBOT_KEYSTORE_PASSWORD and POCKETBOT_KEY_PASSWORD, read from the environment by apksigner);
# otherwise the debug key in POCKETBOT_DEBUG_KEYSTORE, by default ~/.android/debug.keystore (where the Android SDK
# keeps it), made once if missing. Either stays the same across `mvn clean`, so a build installs over the last one.
set -euo pipefail

HERE="$(cd "$(dirname "$0")" && pwd)"
MIN_SDK=26
TARGET_SDK=35
PACKAGE=org.pocketbot.android
APK="$BUILD_DIR/pocketbot.apk"
# MAJOR.MINOR.PATCH[-QUALIFIER] -> MAJOR*1000000 + MINOR*1000 + PATCH: every release has a higher code than the ones
# before it, so Android installs it as an update (a -SNAPSHOT has its release's code: it installs over it with -r).
[[ "$VERSION_NAME" =~ ^([0-9]+)\.([0-9]+)\.([0-9]+)(-.*)?$ ]] || { echo "apk.sh: version $VERSION_NAME is not MAJOR.MINOR.PATCH" >&2; exit 1; }
VERSION_CODE=$((BASH_REMATCH[1] * 1000000 + BASH_REMATCH[2] * 1000 + BASH_REMATCH[3]))
# R8 on C1 only: it runs once per build, so C2's warm-up never pays off (about 2x faster on 2 cores).
R8=("$JAVA" -XX:TieredStopAtLevel=1 -XX:+UseParallelGC -Xmx2g -cp "$R8_JAR")

fail() { echo "apk.sh: $*" >&2; exit 1; }

resources() {
  mkdir -p "$BUILD_DIR"
  aapt2 compile --dir "$HERE/src/main/res" -o "$BUILD_DIR/res.zip"
  # Debian's aapt2 (Android 10) cannot read API 35's framework table (compact entries, 16-bit offsets): it links
  # against the same table rewritten in the older encoding (tools/arsc-compat.py).
  local platform="$BUILD_DIR/android-$TARGET_SDK-resources.jar"
  [ "$platform" -nt "$ANDROID_JAR" ] || python3 "$HERE/tools/arsc-compat.py" "$ANDROID_JAR" "$platform"
  # The build's manifest, as Android's manifest merger writes it: the source with this build's SDK levels. The
  # Robolectric tests read it too (test_config.properties), so they run the app as the phone does: targeting 35.
  awk -v sdk="    <uses-sdk android:minSdkVersion=\"$MIN_SDK\" android:targetSdkVersion=\"$TARGET_SDK\" />" \
    '/^ *<!--|^ *<(uses-|application)/ && !done { print sdk; print ""; done = 1 } { print }' \
    "$HERE/src/main/AndroidManifest.xml" >"$BUILD_DIR/AndroidManifest.xml"
  aapt2 link -o "$BUILD_DIR/resources.ap_" -I "$platform" \
    --manifest "$BUILD_DIR/AndroidManifest.xml" \
    --version-code "$VERSION_CODE" --version-name "$VERSION_NAME" \
    --proguard "$BUILD_DIR/aapt-rules.pro" \
    "$BUILD_DIR/res.zip" 2> >(grep -v "Unknown chunk type" >&2) # chunks newer than Android 10 it need not read
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
  # The last build, to check that this one installs over it.
  rm -f "$BUILD_DIR/previous.apk"
  [ -f "$APK" ] && mv "$APK" "$BUILD_DIR/previous.apk"
  cp "$BUILD_DIR/resources.ap_" "$unsigned"
  (cd "$BUILD_DIR/dex" && aapt add "$unsigned" classes*.dex >/dev/null)
  if [ -d "$BUILD_DIR/meta/META-INF/services" ]; then
    (cd "$BUILD_DIR/meta" && aapt add "$unsigned" META-INF/services/* >/dev/null)
  fi
  zipalign -p -f 4 "$unsigned" "$aligned"

  signing_key
  apksigner sign --ks "$KEYSTORE" --ks-key-alias "$KEY_ALIAS" --ks-pass "env:$STORE_PASS_VAR" --key-pass "env:$KEY_PASS_VAR" \
    --out "$APK" "$aligned"
  rm -f "$unsigned" "$aligned" "$APK.idsig"

  check
  echo "apk.sh: $APK: $(stat -c %s "$APK") bytes, $(method_count) dex methods, built in $((SECONDS - started)) s"
}

# The key to sign with: KEYSTORE, KEY_ALIAS, and the names of the variables holding the passwords.
signing_key() {
  if [ -n "${POCKETBOT_KEYSTORE:-}" ]; then
    KEYSTORE="$POCKETBOT_KEYSTORE" KEY_ALIAS="${POCKETBOT_KEY_ALIAS:?POCKETBOT_KEY_ALIAS names the release key}"
    STORE_PASS_VAR=POCKETBOT_KEYSTORE_PASSWORD KEY_PASS_VAR=POCKETBOT_KEY_PASSWORD
    [ -f "$KEYSTORE" ] || fail "POCKETBOT_KEYSTORE: no keystore at $KEYSTORE"
    [ -n "${POCKETBOT_KEYSTORE_PASSWORD:-}" ] || fail "POCKETBOT_KEYSTORE_PASSWORD is not set"
    export POCKETBOT_KEY_PASSWORD="${POCKETBOT_KEY_PASSWORD:-$POCKETBOT_KEYSTORE_PASSWORD}"
  else
    # The Android SDK's debug key (alias, passwords and name as Android Studio makes it).
    KEYSTORE="${POCKETBOT_DEBUG_KEYSTORE:-$HOME/.android/debug.keystore}" KEY_ALIAS=androiddebugkey
    STORE_PASS_VAR=DEBUG_PASS KEY_PASS_VAR=DEBUG_PASS
    export DEBUG_PASS=android
    if [ ! -f "$KEYSTORE" ]; then
      mkdir -p "$(dirname "$KEYSTORE")"
      keytool -genkeypair -keystore "$KEYSTORE" -storepass android -keypass android -alias androiddebugkey \
        -keyalg RSA -keysize 2048 -validity 10950 -dname "CN=Android Debug,O=Android,C=US" >/dev/null 2>&1 \
        || fail "keytool could not make the debug key at $KEYSTORE"
      echo "apk.sh: made the debug key $KEYSTORE: keep it, builds signed with another key do not install over these"
    fi
  fi
}

# SHA-256 of the certificate that signed APK $1.
signer() {
  apksigner verify --print-certs "$1" | sed -n 's/^Signer #1 certificate SHA-256 digest: //p'
}

# The APK checks itself: a valid signature by the key meant, the manifest and version as meant, that it installs over
# the previous build, and only the platform API it is allowed to use.
check() {
  apksigner verify --verbose "$APK" >"$BUILD_DIR/apksigner.txt" || fail "apksigner verify failed: $(cat "$BUILD_DIR/apksigner.txt")"
  grep -q "Verified using v2 scheme (APK Signature Scheme v2): true" "$BUILD_DIR/apksigner.txt" \
    || fail "not signed with APK Signature Scheme v2: $(cat "$BUILD_DIR/apksigner.txt")"
  local key
  key=$(keytool -exportcert -keystore "$KEYSTORE" -alias "$KEY_ALIAS" -storepass:env "$STORE_PASS_VAR" | sha256sum | cut -d' ' -f1)
  [ "$(signer "$APK")" = "$key" ] || fail "the APK is not signed by $KEY_ALIAS in $KEYSTORE"

  aapt2 dump badging "$APK" >"$BUILD_DIR/badging.txt" 2>&1 || fail "aapt2 dump badging failed: $(cat "$BUILD_DIR/badging.txt")"
  local want=(
    "package: name='$PACKAGE' versionCode='$VERSION_CODE' versionName='$VERSION_NAME'"
    "sdkVersion:'$MIN_SDK'"
    "targetSdkVersion:'$TARGET_SDK'"
    "uses-permission: name='android.permission.BLUETOOTH_SCAN'"
    "uses-permission: name='android.permission.BLUETOOTH_CONNECT'"
    "uses-permission: name='android.permission.BLUETOOTH' maxSdkVersion='30'"
    "uses-permission: name='android.permission.BLUETOOTH_ADMIN' maxSdkVersion='30'"
    "uses-permission: name='android.permission.ACCESS_FINE_LOCATION' maxSdkVersion='30'"
    "uses-permission: name='android.permission.INTERNET'"
    "uses-permission: name='android.permission.FOREGROUND_SERVICE_CONNECTED_DEVICE'"
    "uses-permission: name='android.permission.POST_NOTIFICATIONS'"
    "launchable-activity: name='$PACKAGE.MainActivity'"
  )
  for line in "${want[@]}"; do
    grep -qF "$line" "$BUILD_DIR/badging.txt" || fail "aapt2 dump badging lacks \"$line\":
$(cat "$BUILD_DIR/badging.txt")"
  done
  ! grep -q "application-debuggable" "$BUILD_DIR/badging.txt" || fail "the APK is debuggable"
  installs_over_previous

  # Every class, method and field the dex uses exists: in Android 15's android-all (android.*) or the JDK (java.*:
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

# Android installs an APK over an installed one of the same package only when it has the same signer and a version
# code not lower: checked against the build this one replaced in target/, if there was one.
installs_over_previous() {
  local previous="$BUILD_DIR/previous.apk"
  [ -f "$previous" ] || return 0
  local code_was
  code_was=$(aapt2 dump badging "$previous" 2>/dev/null | sed -n "s/^package: .* versionCode='\([0-9]*\)'.*/\1/p")
  [ "${code_was:-0}" -le "$VERSION_CODE" ] || fail "version code $VERSION_CODE is lower than the previous build's $code_was"
  if [ "$(signer "$previous")" = "$(signer "$APK")" ]; then
    echo "apk.sh: installs over the previous build (version code $code_was -> $VERSION_CODE, the same signer)"
  else
    # Switching keys (debug to release) is a choice, not a build error; the user must know what it costs.
    echo "apk.sh: WARNING: signed with another key than the previous build: a phone with that one must uninstall it first" >&2
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
