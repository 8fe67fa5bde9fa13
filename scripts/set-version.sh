#!/usr/bin/env bash
# Sets the version of every PocketBot module, and where README.md and samples/outside name it: the libraries, their
# BOM and the applications share one version. Usage: scripts/set-version.sh 0.2.0 (see library/README.md, "Releasing").
set -euo pipefail
new=${1:?usage: scripts/set-version.sh NEW_VERSION}
cd "$(dirname "$0")/.."
old=$(sed -n 's:^  <version>\(.*\)</version>$:\1:p' library/pom.xml)
[ -n "$old" ] || { echo "no version found in library/pom.xml"; exit 1; }
esc() { printf '%s' "$1" | sed 's/[.]/\\./g'; }
for pom in $(git ls-files '*pom.xml'); do
  sed -i -e "s#<version>$(esc "$old")</version>#<version>$new</version>#" \
         -e "s#<pocketbot.version>$(esc "$old")</pocketbot.version>#<pocketbot.version>$new</pocketbot.version>#" "$pom"
done
sed -i "s#$(esc "$old")#$new#g" README.md
echo "version $old -> $new; left alone: CHANGELOG.md (write its heading yourself)"
git grep -n -F "$old" -- '*pom.xml' README.md samples || true
