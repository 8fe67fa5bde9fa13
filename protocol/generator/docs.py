"""docs/protocol.md: the protocol reference, from the prose template protocol/protocol.md.in (beside the
schema) with the tables and figures of the schema filled in.

The template says `{{name}}` where a generated part goes; an unknown name is an error. Names: version,
layout_hash, firmware_version, max_payload, max_frame, crc, settings_size, state_size, frame_table,
packet_table, packets, settings_table, state_table, enums, flags, layout_text_file, and per item:
`id.<packet>` (0xNN), `bytes.<packet>` (the largest frame of that packet on a stream link: SLIP ENDs,
header, payload, CRC, no escapes), `ms.<packet>` (that frame's time at 115200 Bd, 10 bits a byte),
`default.<group>.<field>` (a settings default), `code.<enum>.<value>` and `mask.<flags>.<bit>`."""
import json
import re
from pathlib import Path

from .golden import OUT_LAYOUT
from .model import HEADER

OUT = "docs/protocol.md"
TEMPLATE = Path(__file__).resolve().parent.parent / "protocol.md.in"
BYTES_PER_S_115200 = 11520  # 115200 Bd, 10 bits per byte


def doc_type(model, f):
    if f.is_bytes:
        return f"u8[{f.min_len}..{f.max_len}]"
    if f.enum:
        return f"{f.type_text} ({f.enum})"
    if f.flags:
        return f"{f.type_text} (flags {f.flags})"
    return f.type_text


def flag_text(model, name):
    fl = model.flags[name]
    return "; ".join(f"`{k}` 0x{v:02X}" for k, v in fl["values"].items())


def doc_fields(model, s, offset=0, prefix="", ranges=False, defaults=None):
    rows = []
    for f in s.fields:
        if f.is_struct and not f.count:
            rows += doc_fields(model, f.struct, offset + f.offset, f"{prefix}{f.name}.", ranges, None)
            continue
        rng = ""
        if ranges and f.min is not None:
            rng = f"{f.min:g} .. {f.max:g}"
        d = ""
        if defaults is not None:
            dv = defaults.get(f.name, f.default)
            d = json.dumps(dv) if isinstance(dv, str) else f"{dv:g}" if isinstance(dv, float) else str(dv)
        size = f"{f.size}" if not f.is_bytes else f"{f.min_len}..{f.max_len}"
        meaning = f.doc + (f" (bits: {flag_text(model, f.flags)})" if f.flags else "")
        row = f"| {offset + f.offset} | {size} | `{prefix}{f.name}` | {doc_type(model, f)} | {f.unit} |"
        if ranges:
            row += f" {rng} | {d} |"
        rows.append(row + f" {meaning} |")
    return rows


def frame_table(model):
    return "\n".join([
        "| offset | size | field | meaning |", "|---|---|---|---|",
        "| 0 | 1 | type | packet type (below) |",
        "| 1 | 1 | seq | sequence number: non-zero on host commands that are acknowledged, a rolling counter from the robot |",
        f"| 2 | 1 | length | payload length in bytes, at most {model.max_payload} |",
        "| 3 | length | payload | the packet (below) |",
        f"| 3+length | 2 | crc | {model.schema['frame']['crc']}, little-endian |"])


def packet_table(model):
    o = ["| type | name | direction | payload bytes | acked | from watchers | meaning |", "|---|---|---|---|---|---|---|"]
    for p in model.packets:
        size = f"{p.min_size}..{p.max_size}" if p.variable else str(p.size)
        d = "robot to host" if p.dir == "r2h" else "host to robot"
        acked = ("yes, idempotent" if p.idempotent else "yes") if p.ack else ""
        watchers = "" if p.dir == "r2h" else "yes" if p.watcher_ok else "refused"
        o.append(f"| 0x{p.id:02X} | `{p.name}` | {d} | {size} | {acked} | {watchers} | {p.doc} |")
    return "\n".join(o)


def packets(model):
    o = []
    for p in model.packets:
        o += [f"### 0x{p.id:02X} `{p.name}`", "", p.doc, ""]
        if p.name == "state_full":
            o += ["The payload is `robot_state` (below).", ""]
            continue
        if not p.fields:
            o += ["No payload.", ""]
            continue
        o += ["| offset | size | field | type | unit | meaning |", "|---|---|---|---|---|---|"]
        o += doc_fields(model, p) + [""]
    return "\n".join(o).rstrip("\n")


def settings_table(model):
    o = ["| offset | size | field | type | unit | range | default | meaning |", "|---|---|---|---|---|---|---|---|"]
    for g in model.settings_groups:
        base = model.settings.fields[[x.name for x in model.settings.fields].index(g.name)].offset
        o += doc_fields(model, g.struct, base, g.name + ".", True, g.defaults)
    return "\n".join(o)


def state_table(model):
    return "\n".join(["| offset | size | field | type | unit | meaning |", "|---|---|---|---|---|---|"] +
                     doc_fields(model, model.state))


def enums(model):
    o = []
    for name, e in model.enums.items():
        docs = e.get("docs", {})
        if docs:
            o.append(f"- `{name}`: {e.get('doc', '')}")
            o += [f"  - {k} = {v}: {docs[k]}" if k in docs else f"  - {k} = {v}" for k, v in e["values"].items()]
        else:
            o.append(f"- `{name}`: {e.get('doc', '')} " + ", ".join(f"{k} = {v}" for k, v in e["values"].items()))
    return "\n".join(o)


def flags(model):
    o = []
    for name, fl in model.flags.items():
        users = [f"`{path}`" for path in flag_users(model, name)]
        o.append(f"- `{name}`: {fl.get('doc', '')} Used by {', '.join(users)}.")
        docs = fl.get("docs", {})
        o += [f"  - `{k}` = 0x{v:02X}" + (f": {docs[k]}" if k in docs else "") for k, v in fl["values"].items()]
    return "\n".join(o)


def flag_users(model, name):
    out = []
    def walk(s, prefix):
        for f in s.fields:
            if f.is_struct and not f.count:
                walk(f.struct, f"{prefix}{f.name}.")
            elif f.flags == name:
                out.append(prefix + f.name)
    walk(model.state, "")
    for p in model.packets:
        if p.name != "state_full":
            walk(p, f"{p.name}.")
    return out


def values(model):
    v = {
        "version": str(model.version), "layout_hash": f"0x{model.layout_hash:08X}",
        "firmware_version": ".".join(map(str, model.fw_version)), "max_payload": str(model.max_payload),
        "max_frame": str(model.max_payload + 5), "crc": model.schema["frame"]["crc"],
        "settings_size": str(model.settings.size), "state_size": str(model.state.size),
        "frame_table": frame_table(model), "packet_table": packet_table(model), "packets": packets(model),
        "settings_table": settings_table(model), "state_table": state_table(model), "enums": enums(model),
        "flags": flags(model), "layout_text_file": OUT_LAYOUT,
    }
    for p in model.packets:
        v[f"id.{p.name}"] = f"0x{p.id:02X}"
        frame = 2 + 3 + p.max_size + 2
        v[f"bytes.{p.name}"] = str(frame)
        v[f"ms.{p.name}"] = f"{frame * 1000 / BYTES_PER_S_115200:.1f}"
    for path, f, _, d in model.settings_leaves():
        v[f"default.{path}"] = f"{d:g}" if isinstance(d, float) else str(d)
    for name, e in model.enums.items():
        for k, code in e["values"].items():
            v[f"code.{name}.{k}"] = str(code)
    for name, fl in model.flags.items():
        for k, mask in fl["values"].items():
            v[f"mask.{name}.{k}"] = f"0x{mask:02X}"
    return v


def emit(model):
    vals = values(model)
    def fill(m):
        key = m.group(1)
        if key not in vals:
            raise KeyError(f"{TEMPLATE.name}: unknown placeholder {{{{{key}}}}}")
        return vals[key]
    text = re.sub(r"\{\{([a-z0-9_.]+)\}\}", fill, TEMPLATE.read_text())
    return {OUT: f"<!-- {HEADER} Prose: protocol/protocol.md.in. -->\n" + text}
