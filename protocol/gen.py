#!/usr/bin/env python3
"""Generates every artefact of the PocketBot protocol from protocol/pocketbot.toml.

    python3 protocol/gen.py          write the generated files
    python3 protocol/gen.py --check  fail (exit 1) when any generated file is stale

The work is done by the package protocol/generator: model.py reads the schema, and one emitter per output
writes the firmware's C header and tables, the SDK's Kotlin codecs, the SDK's public state model and settings tree
(sdk_model.py, sdk_settings.py), docs/protocol.md, the golden byte vectors (protocol/golden/vectors.json) and the tests that decode them on every side (C, Kotlin common,
Javolution Struct on the JVM).
"""
import sys
from pathlib import Path

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, str(Path(__file__).resolve().parent))

import generator  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SCHEMA = ROOT / "protocol" / "pocketbot.toml"


def main():
    model = generator.load(SCHEMA)
    outputs = generator.generate(model)
    check = "--check" in sys.argv[1:]
    stale = []
    for rel, content in outputs.items():
        path = ROOT / rel
        data = content.encode() if isinstance(content, str) else content
        if path.exists() and path.read_bytes() == data:
            continue
        if check:
            stale.append(rel)
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
            print(f"wrote {rel}")
    if stale:
        print("stale generated files (run `python3 protocol/gen.py` and commit):\n  " + "\n  ".join(stale))
        sys.exit(1)
    if check:
        print(f"protocol: {len(outputs)} generated files up to date "
              f"({len(model.packets)} packets, settings {model.settings.size} B, state {model.state.size} B)")


if __name__ == "__main__":
    main()
