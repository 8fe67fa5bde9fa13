"""firmware/tests/golden_vectors.h: the golden frames and their payloads as C initializers."""
from .c_code import c_init
from .model import HEADER

OUT = "firmware/tests/golden_vectors.h"


def emit(model, vectors):
    by_name = {p.name: p for p in model.packets}
    o = [f"/* {HEADER} */", "/* Golden vectors: frames packed by protocol/gen.py (Python struct), payloads as C initializers. */",
         "#ifndef GOLDEN_VECTORS_H", "#define GOLDEN_VECTORS_H", "", '#include "pb_protocol.h"', "",
         "typedef struct { const char *name; uint8_t type; uint8_t seq; const uint8_t *frame; uint16_t frame_len;",
         "                 const uint8_t *slip; uint16_t slip_len; const void *payload; uint8_t payload_len; } pb_golden_t;", ""]
    for v in vectors:
        p = by_name[v["packet"]]
        frame, sl = bytes.fromhex(v["frame"]), bytes.fromhex(v["slip"])
        o.append(f"static const uint8_t golden_{v['name']}_frame[] = {{{', '.join(f'0x{b:02x}' for b in frame)}}};")
        o.append(f"static const uint8_t golden_{v['name']}_slip[] = {{{', '.join(f'0x{b:02x}' for b in sl)}}};")
        o.append(f"static const {p.c_name} golden_{v['name']}_payload = {c_init(p, v['values'])};")
    o += ["", "static const pb_golden_t pb_golden[] = {"]
    for v in vectors:
        p = by_name[v["packet"]]
        n = v["name"]
        o.append(f"    {{\"{n}\", PB_PKT_{p.name.upper()}, {v['seq']}, golden_{n}_frame, sizeof golden_{n}_frame, "
                 f"golden_{n}_slip, sizeof golden_{n}_slip, &golden_{n}_payload, {len(v['payload']) // 2}}},")
    o += ["};", f"#define PB_GOLDEN_COUNT {len(vectors)}", "", "#endif", ""]
    return {OUT: "\n".join(o)}
