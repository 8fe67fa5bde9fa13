#!/usr/bin/env bash
# Installs Bumble (pinned in emulator/bluetooth/requirements.txt) into a virtual environment of its own,
# build/bumble/venv, for the virtual Bluetooth controllers and gateway (emulator/bluetooth/). Idempotent and
# fast when present: the venv keeps a copy of the requirements it was made from, and is rebuilt only when they
# changed. Prints the venv's python on stdout, so callers can use `$(scripts/ensure-bumble.sh)`.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
req="$root/emulator/bluetooth/requirements.txt"
venv="$root/build/bumble/venv"
stamp="$venv/pocketbot-requirements.txt"

if [ -x "$venv/bin/python" ] && cmp -s "$req" "$stamp"; then
  echo "$venv/bin/python"
  exit 0
fi

# python3 -m venv needs Debian's python3-venv (ensurepip) when python3 is the system one.
if ! python3 -c 'import ensurepip, venv' >/dev/null 2>&1; then
  bash "$root/scripts/ensure-deps.sh" >&2
fi
echo "ensure-bumble: installing Bumble into $venv" >&2
rm -rf "$venv"
mkdir -p "$(dirname "$venv")"
python3 -m venv "$venv" >&2
# --no-deps: the requirements list every package with its version, so nothing unpinned comes in.
"$venv/bin/pip" install --quiet --disable-pip-version-check --no-deps -r "$req" >&2
"$venv/bin/python" -c 'import bumble.controller, bumble.device' >&2
cp "$req" "$stamp"
echo "$venv/bin/python"
