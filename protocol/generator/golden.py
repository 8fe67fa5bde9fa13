"""Golden vectors: deterministic example values for every packet, packed with Python's `struct`,
independently of the C compiler and of the Kotlin codecs they check (protocol/golden/vectors.json)."""
import json
import random
import struct
import zlib

from .model import HEADER, PRIMS, PRIM_RANGE, crc16, slip

OUT = "protocol/golden/vectors.json"
OUT_LAYOUT = "protocol/golden/layout.txt"


def pack_value(field, value):
    if field.is_bytes:
        return bytes(value)
    if field.is_char:
        raw = value.encode()
        assert len(raw) <= field.count
        return raw + bytes(field.count - len(raw))
    if field.count:
        return b"".join(pack_scalar(field, v) for v in value)
    return pack_scalar(field, value)


def pack_scalar(field, value):
    if field.is_struct:
        return pack_struct(field.struct, value)
    return struct.pack("<" + PRIMS[field.base][0], value)


def pack_struct(s, values):
    return b"".join(pack_value(f, values[f.name]) for f in s.fields)


def example_scalar(model, field, rng):
    if field.is_struct:
        return example_struct(model, field.struct, rng)
    if field.enum:
        return rng.choice(list(model.enum_values(field.enum).values()))
    if field.base == "f32":
        # A multiple of 1/64 is exact in binary32, so every side prints the same value.
        return rng.randint(-64000, 64000) / 64.0
    lo, hi = PRIM_RANGE[field.base]
    return rng.randint(lo, hi)


def example_value(model, field, rng):
    if field.is_bytes:
        return [rng.randint(0, 255) for _ in range(rng.randint(max(1, field.min_len), field.max_len))]
    if field.is_char:
        return rng.choice(["PocketBot-7", "Alpha", "robot \u00e9", ""])[: field.count]
    if field.count:
        return [example_scalar(model, field, rng) for _ in range(field.count)]
    return example_scalar(model, field, rng)


def example_struct(model, s, rng):
    values = {f.name: example_value(model, f, rng) for f in s.fields}
    for f in s.fields:
        if f.length_of:
            values[f.name] = len(values[f.length_of])
    return values


def vectors(model):
    out = []
    for p in model.packets:
        for variant in range(2 if p.variable or p.name == "state_full" else 1):
            rng = random.Random(zlib.crc32(f"{p.name}/{variant}".encode()))
            values = example_struct(model, p, rng)
            if variant == 0 and p.variable:
                # Bytes that SLIP must escape, so the stream form is witnessed too.
                values[p.fields[-1].name] = ([0xC0, 0xDB, 0x00, 0xDC] * 30)[: p.fields[-1].max_len]
                for f in p.fields:
                    if f.length_of:
                        values[f.name] = len(values[f.length_of])
            seq = rng.randint(1, 255) if p.dir == "h2r" and p.ack else rng.randint(0, 255) if p.dir == "r2h" else 0
            payload = pack_struct(p, values)
            head = bytes([p.id, seq, len(payload)]) + payload
            frame = head + struct.pack("<H", crc16(head))
            out.append({"name": f"{p.name}_{variant}", "packet": p.name, "seq": seq, "values": values,
                        "payload": payload.hex(), "frame": frame.hex(), "slip": slip(frame).hex()})
    return out


def emit(model, vecs):
    return {OUT: json.dumps({"note": HEADER, "vectors": vecs}, indent=1, ensure_ascii=False) + "\n",
            # The exact text the layout hash is the FNV-1a of: anyone can check a hash against it.
            OUT_LAYOUT: model.layout_text()}
