"""sdk/jvm's JavolutionWitnessTest.kt: an outside witness of the byte layout (Javolution's Struct)."""
import json
import struct

from .model import HEADER, camel

OUT = "sdk/jvm/src/test/kotlin/org/pocketbot/protocol/JavolutionWitnessTest.kt"

JAVOLUTION_TYPES = {"u8": "Unsigned8", "i8": "Signed8", "u16": "Unsigned16", "i16": "Signed16",
                    "u32": "Unsigned32", "i32": "Signed32", "f32": "Float32"}


def flat_leaves(s, values, prefix=""):
    """(path, field, value) for every primitive leaf of a struct, arrays and nested structs flattened."""
    out = []
    for f in s.fields:
        v = values[f.name]
        path = prefix + f.name
        if f.is_struct:
            items = v if f.count else [v]
            for i, item in enumerate(items):
                out += flat_leaves(f.struct, item, f"{path}{i}_" if f.count else path + "_")
        elif f.is_bytes or (f.count and not f.is_char):
            out += [(f"{path}{i}", f, x) for i, x in enumerate(v)]
        else:
            out.append((path, f, v))
    return out


def emit(model, vectors):
    by_name = {p.name: p for p in model.packets}
    o = [f"// {HEADER}", "package org.pocketbot.protocol", "",
         "import java.nio.ByteBuffer", "import java.nio.ByteOrder", "import javolution.io.Struct",
         "import kotlin.test.Test", "import kotlin.test.assertEquals", "",
         "/**",
         " * An outside witness of the byte layout: Javolution 5.5.1's Struct (the thesis's own library), little-endian",
         " * and packed, reads every golden payload and must find the schema's values at the schema's offsets.",
         " */",
         "class JavolutionWitnessTest {",
         "    private fun hex(s: String): ByteArray = ByteArray(s.length / 2) { s.substring(2 * it, 2 * it + 2).toInt(16).toByte() }",
         "",
         "    private abstract class LePacked : Struct() {",
         "        override fun byteOrder(): ByteOrder = ByteOrder.LITTLE_ENDIAN",
         "        override fun isPacked(): Boolean = true",
         "    }", ""]
    for v in vectors:
        p = by_name[v["packet"]]
        leaves = flat_leaves(p, v["values"])
        cls = camel(v["name"], True)
        o.append(f"    private class {cls} : LePacked() {{")
        for path, f, val in leaves:
            if f.is_char:
                o.append(f"        val {path} = UTF8String({f.count})")
            else:
                jt = "Unsigned8" if f.is_bytes else JAVOLUTION_TYPES[f.base]
                o.append(f"        val {path} = {jt}()")
        o.append("    }")
        o.append("")
        o.append(f"    @Test fun {camel(v['name'])}() {{")
        o.append(f"        val bytes = hex(\"{v['payload']}\")")
        o.append(f"        val s = {cls}()")
        o.append(f"        assertEquals(bytes.size, s.size(), \"{p.name} size\")")
        o.append("        s.setByteBuffer(ByteBuffer.wrap(bytes).order(ByteOrder.LITTLE_ENDIAN), 0)")
        for path, f, val in leaves:
            if f.is_char:
                exp = json.dumps(val, ensure_ascii=False).replace("$", "\\$")
            elif f.is_bytes:
                exp = str(val) + ".toShort()"
            elif f.base == "f32":
                exp = f"Float.fromBits(0x{struct.unpack('<I', struct.pack('<f', val))[0]:08x}.toInt())"
            elif f.base in ("u32",):
                exp = f"{val}L"
            elif f.base == "u8":
                exp = f"{val}.toShort()"
            elif f.base == "i8":
                exp = f"({val}).toByte()"
            elif f.base == "i16":
                exp = f"({val}).toShort()"
            elif f.base == "i32" and val == -2**31:
                exp = "Int.MIN_VALUE"
            else:
                exp = str(val)
            o.append(f"        assertEquals({exp}, s.{path}.get(), \"{p.name}.{path}\")")
        o.append("    }")
        o.append("")
    o += ["}", ""]
    return {OUT: "\n".join(o)}
