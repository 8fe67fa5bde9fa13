"""The firmware's C header (pb_protocol.h: constants, packed structs with static asserts) and tables
(pb_protocol_tables.c: packet sizes and directions, settings leaves with their ranges, the defaults)."""
import json
import struct

from .model import HEADER, PRIMS

OUT_HEADER = "firmware/protocol/pb_protocol.h"
OUT_TABLES = "firmware/protocol/pb_protocol_tables.c"


def c_flag_prefix(name):
    """line_flags -> PB_LINE_FLAG: a constant names one flag."""
    n = name.upper()
    return "PB_" + (n[:-1] if n.endswith("_FLAGS") else n)


def c_field_decl(f):
    if f.is_bytes:
        return f"uint8_t {f.name}[{f.max_len}]"
    if f.is_char:
        return f"char {f.name}[{f.count}]"
    t = PRIMS[f.base][2] if f.is_prim else f.struct.c_name
    return f"{t} {f.name}" + (f"[{f.count}]" if f.count else "")


def c_struct(s):
    out = [f"/** {s.doc} */", "typedef struct PB_PACKED {"]
    for f in s.fields:
        unit = f" [{f.unit}]" if f.unit else ""
        out.append(f"    {c_field_decl(f)}; /**< {f.doc}{unit} */")
    out.append(f"}} {s.c_name};")
    out.append(f"PB_STATIC_ASSERT(sizeof({s.c_name}) == {s.max_size if s.variable else s.size}, \"{s.c_name} size\");")
    for f in s.fields:
        out.append(f"PB_STATIC_ASSERT(offsetof({s.c_name}, {f.name}) == {f.offset}, \"{s.c_name}.{f.name} offset\");")
    return "\n".join(out)


def header(model):
    o = [f"/* {HEADER} */", "/**", " * \\file pb_protocol.h",
         " * The PocketBot wire protocol: packets, settings and robot_state, little-endian and packed.",
         " * See docs/protocol.md. Frame = type, seq, payload length, payload, CRC-16/CCITT-FALSE (LE).", " */",
         "#ifndef PB_PROTOCOL_H", "#define PB_PROTOCOL_H", "", "#include <stddef.h>", "#include <stdint.h>", "",
         "#define PB_PACKED __attribute__((packed))",
         "#define PB_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)", "",
         "#ifdef __AVR__", "#define PB_FLASH __flash", "#else", "#define PB_FLASH", "#endif", "",
         f"#define PB_PROTOCOL_VERSION {model.version}",
         f"#define PB_FW_MAJOR {model.fw_version[0]}", f"#define PB_FW_MINOR {model.fw_version[1]}",
         f"#define PB_FW_PATCH {model.fw_version[2]}",
         f"#define PB_LAYOUT_HASH 0x{model.layout_hash:08X}UL",
         "#define PB_FRAME_HEADER_SIZE 3", "#define PB_FRAME_CRC_SIZE 2",
         f"#define PB_MAX_PAYLOAD {model.max_payload}",
         "#define PB_MAX_FRAME (PB_FRAME_HEADER_SIZE + PB_MAX_PAYLOAD + PB_FRAME_CRC_SIZE)", ""]
    for name, e in model.enums.items():
        o.append(f"/* {name}: {e.get('doc', '')} */")
        for k, v in e["values"].items():
            o.append(f"#define PB_{name.upper()}_{k.upper()} {v}")
        o.append("")
    for name, fl in model.flags.items():
        o.append(f"/* {name}: {fl.get('doc', '')} */")
        for k, v in fl["values"].items():
            o.append(f"#define {c_flag_prefix(name)}_{k.upper()} 0x{v:02X}u")
        o.append("")
    o.append("/* Packet types */")
    for p in model.packets:
        o.append(f"#define PB_PKT_{p.name.upper()} 0x{p.id:02X} /**< {p.dir}{', acked' if p.ack else ''} */")
    o.append("")
    for s in model.structs.values():
        if s.name != "robot_state":
            o += [c_struct(s), ""]
    o += [c_struct(model.settings), "", c_struct(model.state), ""]
    for p in model.packets:
        o += [c_struct(p)]
        if p.variable:
            o.append(f"#define PB_{p.name.upper()}_HEAD_SIZE {p.size} /**< the fixed fields before the tail */")
            o.append(f"#define PB_{p.name.upper()}_MIN_SIZE {p.min_size}")
            o.append(f"#define PB_{p.name.upper()}_MAX_SIZE {p.max_size}")
        else:
            o.append(f"#define PB_{p.name.upper()}_SIZE {p.size}")
        o.append("")
    o += ["/* Tables (pb_protocol_tables.c) */",
          "/** A packet type: payload size bounds, direction, acknowledged, idempotent (a read: answered every time),",
          " *  watcher_ok (obeyed from a host that only watches). */",
          "typedef struct { uint8_t type; uint8_t min_size; uint8_t max_size; uint8_t dir; uint8_t needs_ack; uint8_t idempotent; uint8_t watcher_ok; } pb_packet_info_t;",
          "#define PB_DIR_R2H 0", "#define PB_DIR_H2R 1",
          f"#define PB_PACKET_INFO_COUNT {len(model.packets)}",
          "extern const PB_FLASH pb_packet_info_t pb_packet_info[PB_PACKET_INFO_COUNT];", "",
          "enum { PB_FIELD_U8, PB_FIELD_I8, PB_FIELD_U16, PB_FIELD_I16, PB_FIELD_U32, PB_FIELD_I32, PB_FIELD_F32, PB_FIELD_CHAR };",
          "/** One leaf of settings: where it is, what it is, and the range a write must respect. */",
          "typedef struct { uint16_t offset; uint8_t elem_size; uint8_t count; uint8_t type; float min; float max; } pb_settings_field_t;",
          f"#define PB_SETTINGS_FIELD_COUNT {len(model.settings_leaves())}",
          "extern const PB_FLASH pb_settings_field_t pb_settings_fields[PB_SETTINGS_FIELD_COUNT];",
          "extern const PB_FLASH pb_settings_t pb_settings_defaults;", "", "#endif", ""]
    return "\n".join(o)


def c_float(v):
    """An exact C literal of the binary32 nearest to v."""
    return struct.unpack("<f", struct.pack("<f", v))[0].hex() + "f"


def c_value(field, value):
    if field.is_bytes or (field.count and not field.is_char):
        inner = ", ".join(c_scalar(field, v) for v in value)
        return "{" + inner + "}"
    if field.is_char:
        return json.dumps(value)
    return c_scalar(field, value)


def c_scalar(field, v):
    if field.is_struct:
        return c_init(field.struct, v)
    if field.base == "f32":
        return c_float(v)
    if field.base == "u32":
        return f"{v}UL"
    if field.base == "i32":
        return f"{v}L" if v != -2**31 else "(-2147483647L - 1)"
    return str(v)


def c_init(s, values):
    return "{" + ", ".join(f".{f.name} = {c_value(f, values[f.name])}" for f in s.fields) + "}"


def tables(model):
    type_code = {"u8": "PB_FIELD_U8", "i8": "PB_FIELD_I8", "u16": "PB_FIELD_U16", "i16": "PB_FIELD_I16",
                 "u32": "PB_FIELD_U32", "i32": "PB_FIELD_I32", "f32": "PB_FIELD_F32"}
    o = [f"/* {HEADER} */", '#include "pb_protocol.h"', "",
         "const PB_FLASH pb_packet_info_t pb_packet_info[PB_PACKET_INFO_COUNT] = {"]
    for p in model.packets:
        o.append(f"    {{PB_PKT_{p.name.upper()}, {p.min_size}, {p.max_size}, "
                 f"PB_DIR_{p.dir.upper()}, {1 if p.ack else 0}, {1 if p.idempotent else 0}, {1 if p.watcher_ok else 0}}},")
    o += ["};", "", "const PB_FLASH pb_settings_field_t pb_settings_fields[PB_SETTINGS_FIELD_COUNT] = {"]
    for path, f, off, _ in model.settings_leaves():
        t = "PB_FIELD_CHAR" if f.is_char else type_code[f.base]
        lo = c_float(f.min if f.min is not None else -3.4e38)
        hi = c_float(f.max if f.max is not None else 3.4e38)
        o.append(f"    {{{off}, {f.elem_size}, {f.count or 1}, {t}, {lo}, {hi}}}, /* {path} */")
    o += ["};", "", "const PB_FLASH pb_settings_t pb_settings_defaults = {"]
    for g in model.settings_groups:
        vals = {}
        for f in g.struct.fields:
            d = g.defaults.get(f.name, f.default)
            vals[f.name] = [d] * f.count if f.count and not f.is_char else d
        o.append(f"    .{g.name} = {c_init(g.struct, vals)},")
    o += ["};", ""]
    return "\n".join(o)


def emit(model):
    return {OUT_HEADER: header(model), OUT_TABLES: tables(model)}
