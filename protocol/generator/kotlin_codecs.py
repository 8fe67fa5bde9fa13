"""The SDK's Kotlin codecs (sdk/protocol/.../Protocol.kt): enums, structs, packets, the packet table,
the settings leaves and the defaults, in plain common Kotlin."""
import json
import struct

from .model import HEADER, PRIMS, camel

OUT = "sdk/protocol/src/commonMain/kotlin/org/pocketbot/protocol/Protocol.kt"

def kt_enum_typed(f, typed):
    """A single enum field of a state struct: typed as the Kotlin enum (settings and packets keep raw codes)."""
    return typed and f.enum is not None and not f.count and f.is_prim


def kt_type(f, typed=False):
    if f.is_bytes:
        return "ByteArray"
    if f.is_char:
        return "String"
    if kt_enum_typed(f, typed):
        return camel(f.enum, True)
    t = PRIMS[f.base][3] if f.is_prim else f.struct.kt_name
    return f"List<{t}>" if f.count else t


INT_PRIMS = {"u8", "i8", "u16", "i16", "i32"}  # Kotlin Int on the wire types: arrays of them are IntArray-backed


def kt_at(off):
    return f"at + {off}" if off else "at"


def kt_read(f, typed=False):
    """A decode expression for field f of a struct that starts at `at` in `b` (a packet's payload ends at `end`)."""
    at = kt_at(f.offset)
    if f.is_bytes:
        return f"b.copyOfRange({at}, end)"
    if f.is_char:
        return f"b.text({at}, {f.count})"
    if kt_enum_typed(f, typed):
        return f"{camel(f.enum, True)}.fromCode(b.{f.base}({at}))"
    if not f.count:
        return f"{f.struct.kt_name}.decode(b, {at})" if f.is_struct else f"b.{f.base}({at})"
    el = f"{at} + {f.elem_size} * it" if f.elem_size > 1 else f"{at} + it"
    if f.is_struct:
        return f"List({f.count}) {{ {f.struct.kt_name}.decode(b, {el}) }}"
    if f.base in INT_PRIMS:
        return f"IntArrayList(IntArray({f.count}) {{ b.{f.base}({el}) }})"
    return f"List({f.count}) {{ b.{f.base}({el}) }}"


def kt_write(f, expr, typed=False):
    at = kt_at(f.offset)
    if f.is_bytes:
        return f"{expr}.copyInto(b, {at})"
    if f.is_char:
        return f"b.putText({at}, {expr}, {f.count})"
    put = f"put{f.base.upper()}" if f.is_prim else None
    if kt_enum_typed(f, typed):
        return f"b.{put}({at}, {expr}.code)"
    if not f.count:
        return f"{expr}.encodeTo(b, {at})" if f.is_struct else f"b.{put}({at}, {expr})"
    el = f"{at} + {f.elem_size} * i" if f.elem_size > 1 else f"{at} + i"
    if f.is_prim and f.base in INT_PRIMS:
        return (f"intsOf({expr}, {f.count}, \"{f.name}\").let {{ a -> for (i in 0 until {f.count}) b.{put}({el}, a[i]) }}")
    one = f"{expr}[i].encodeTo(b, {el})" if f.is_struct else f"b.{put}({el}, {expr}[i])"
    return (f"require({expr}.size == {f.count}) {{ \"{f.name} needs {f.count} values\" }}; "
            f"for (i in 0 until {f.count}) {one}")


def kt_doc_line(model, f):
    unit = f", in {f.unit}" if f.unit else ""  # not "[ms]": KDoc would read a link to a declaration "ms"
    enum = f" (see [{camel(f.enum, True)}])" if f.enum else ""
    flags = f" (bits: [{camel(f.flags, True)}])" if f.flags else ""
    return f"/** {f.doc}{unit}{enum}{flags} */"


def kt_members(s, typed):
    """equals, hashCode and toString over the constructor properties (what a data class has, minus copy and
    componentN: adding a field later breaks no caller)."""
    fields = [f for f in s.fields if not f.length_of]
    def eq(f):
        n = camel(f.name)
        if f.is_bytes:
            return f"{n}.contentEquals(other.{n})"
        if f.base == "f32" and not f.count:
            return f"{n}.equals(other.{n})"  # as a data class compares floats: NaN equals NaN
        return f"{n} == other.{n}"
    def hash_of(f):
        n = camel(f.name)
        return f"{n}.contentHashCode()" if f.is_bytes else f"{n}.hashCode()"
    def show(f):
        n = camel(f.name)
        return f"{n}=" + ("${" + n + ".toHex()}" if f.is_bytes else "$" + n)
    o = [f"    override fun equals(other: Any?): Boolean =",
         f"        this === other || other is {s.kt_name} && " + " && ".join(eq(f) for f in fields)]
    o.append("    override fun hashCode(): Int {")
    o.append(f"        var h = {hash_of(fields[0])}")
    for f in fields[1:]:
        o.append(f"        h = 31 * h + {hash_of(f)}")
    o.append("        return h")
    o.append("    }")
    o.append(f"    override fun toString(): String = \"{s.kt_name}(" + ", ".join(show(f) for f in fields) + ")\"")
    return o


def kt_class(model, s, packet=False):
    typed = not packet and s.name in model.typed_structs
    o = [f"/** {s.doc} */"]
    params = []
    for f in s.fields:
        if f.length_of:
            continue  # derived from the tail it counts
        params.append(f"    {kt_doc_line(model, f)}\n    public val {camel(f.name)}: {kt_type(f, typed)},")
    has_bytes = any(f.is_bytes for f in s.fields)
    # Structs are plain classes (no copy/componentN, so a new field breaks no caller); packets are data classes
    # unless a ByteArray needs content equality.
    kind = "data class" if packet and not has_bytes else "class"
    parents = " : Packet" if packet else ""
    if not params:
        o.append(f"public data object {s.kt_name}{parents} {{")
    else:
        o.append(f"public {kind} {s.kt_name}(")
        o += params
        o.append(f"){parents} {{")
    for f in s.fields:
        if f.is_bytes:
            n = camel(f.name)
            o.append("    init {")
            o.append(f"        require({n}.size in {f.min_len}..{f.max_len}) {{ \"{f.name}: ${{{n}.size}} bytes, not {f.min_len}..{f.max_len}\" }}")
            o.append("    }")
    if packet:
        o.append(f"    override val type: Int get() = {s.id}")
        tail = [f for f in s.fields if f.is_bytes]
        size = f"{s.size} + {camel(tail[0].name)}.size" if tail else f"{s.size}"
        o.append("    /** Encoded payload size in bytes. */")
        o.append(f"    internal val payloadSize: Int get() = {size}")
    if not s.fields:
        o.append("    @Suppress(\"UNUSED_PARAMETER\") // no payload")
    # Structs (settings, state) are encoded and decoded by the SDK and tools; packets only through Frames.
    vis = "internal" if packet else "public"
    if not packet:
        o.append(f"    /** Writes the [SIZE] bytes of this struct into [b] at [at]. */")
    o.append(f"    {vis} fun encodeTo(b: ByteArray, at: Int) {{")
    for f in s.fields:
        if f.length_of:
            o.append(f"        b.putU8({kt_at(f.offset)}, {camel(f.length_of)}.size)")
        else:
            o.append(f"        {kt_write(f, camel(f.name), typed)}")
    o.append("    }")
    if packet:
        o.append("    override fun encodePayload(): ByteArray = ByteArray(payloadSize).also { encodeTo(it, 0) }")
    if params and (has_bytes or not packet):
        o += kt_members(s, typed)
    c = [f"/** Encoded size in bytes{' without the variable tail' if s.variable else ''}. */",
         f"public const val SIZE: Int = {s.size}"]
    if packet:
        c += ["/** Packet type. */", f"public const val TYPE: Int = {s.id}",
              f"internal const val PAYLOAD_SIZE_MAX: Int = {s.max_size}"]
    sig = "b: ByteArray, at: Int, end: Int" if packet else "b: ByteArray, at: Int"
    if packet:
        c.append("/** Decodes the payload in `b` from [at] to [end], whose length the caller checked against [PACKET_SPECS]. */")
    else:
        c.append("/** Decodes [SIZE] bytes at [at]; the caller checked that they are there. */")
    if packet and not s.variable:
        c.append("@Suppress(\"UNUSED_PARAMETER\") // a fixed-size payload ends where its size says")
    if not params:
        c.append(f"{vis} fun decode({sig}): {s.kt_name} = {s.kt_name}")
    else:
        c.append(f"{vis} fun decode({sig}): {s.kt_name} {{")
        for f in s.fields:
            if f.is_bytes:
                counted = [x for x in s.fields if x.length_of == f.name]
                if counted:
                    n = camel(counted[0].name)
                    c.append(f"    if ({n} != end - ({kt_at(f.offset)})) throw LengthMismatch({n}, end - ({kt_at(f.offset)}))")
            c.append(f"    val {camel(f.name)} = " + (f"b.u8({kt_at(f.offset)})" if f.length_of else kt_read(f, typed)))
        args = ", ".join(camel(f.name) for f in s.fields if not f.length_of)
        c.append(f"    return {s.kt_name}({args})")
        c.append("}")
    if params:  # a packet without fields is a data object: its constants live in the object itself
        o.append("    public companion object {")
        o += ["        " + line for line in c]
        o.append("    }")
    else:
        o += ["    " + line for line in c]
    o.append("}")
    return "\n".join(o)


def kt_literal(model, s, f, v):
    if f.is_bytes:
        return "byteArrayOf(" + ", ".join(str(b - 256 if b > 127 else b) for b in v) + ")"
    if f.is_char:
        return json.dumps(v, ensure_ascii=False).replace("$", "\\$")
    if kt_enum_typed(f, s.name in model.typed_structs):
        name = {code: k for k, code in model.enum_values(f.enum).items()}[v]
        return f"{camel(f.enum, True)}.{name.upper()}"
    if f.count:
        return "listOf(" + ", ".join(kt_scalar(model, f, x) for x in v) + ")"
    return kt_scalar(model, f, v)


def kt_scalar(model, f, v):
    if f.is_struct:
        return kt_construct(model, f.struct, v)
    if f.base == "f32":
        return f"Float.fromBits(0x{struct.unpack('<I', struct.pack('<f', v))[0]:08x}.toInt())"
    if f.base == "u32":
        return f"{v}L"
    if f.base == "i32" and v == -2**31:
        return "Int.MIN_VALUE"
    return str(v)


def kt_construct(model, s, values):
    args = ", ".join(kt_literal(model, s, f, values[f.name]) for f in s.fields if not f.length_of)
    return f"{s.kt_name}({args})" if args else s.kt_name


def kt_enum(name, e):
    cls = camel(name, True)
    docs = e.get("docs", {})
    values = dict(e["values"])
    own_unknown = "unknown" in values
    o = [f"/**", f" * {e.get('doc', '')}",
         f" * [fromCode] maps a code this side does not know to [UNKNOWN]" +
         (" (code -1, never sent by the robot)." if not own_unknown else "."), " */",
         f"public enum class {cls}(public val code: Int) {{"]
    entries = [(k, v) for k, v in values.items()]
    if not own_unknown:
        entries.append(("unknown", -1))
    for i, (k, v) in enumerate(entries):
        doc = docs.get(k) or ("a code this side does not know" if k == "unknown" and not own_unknown else None)
        if doc:
            o.append(f"    /** {doc[:1].upper() + doc[1:]}. */")
        o.append(f"    {k.upper()}({v})" + (";" if i == len(entries) - 1 else ","))
    o.append("    public companion object {")
    o.append(f"        /** The value with this wire code; [UNKNOWN] for a code this side does not know. */")
    o.append(f"        public fun fromCode(code: Int): {cls} = when (code) {{")
    for k, v in values.items():
        o.append(f"            {v} -> {k.upper()}")
    o.append("            else -> UNKNOWN")
    o.append("        }")
    o.append("    }")
    o.append("}")
    return o


def kt_flags(name, fl):
    docs = fl.get("docs", {})
    o = [f"/** {fl.get('doc', '')} Bit masks of the fields marked with it. */", f"public object {camel(name, True)} {{"]
    for k, v in fl["values"].items():
        if k in docs:
            o.append(f"    /** {docs[k][:1].upper() + docs[k][1:]}. */")
        o.append(f"    public const val {k.upper()}: Int = 0x{v:02X}")
    o.append("}")
    return o


def codecs(model):
    o = [f"// {HEADER}", "package org.pocketbot.protocol", "",
         "/** Constants of the protocol this SDK speaks. */",
         "public object ProtocolInfo {",
         f"    public const val VERSION: Int = {model.version}",
         f"    /** Hash of every packet, settings and state layout; compared with the robot's `hello`. */",
         f"    public const val LAYOUT_HASH: Long = 0x{model.layout_hash:08X}L",
         f"    /** Firmware version this SDK was generated with. */",
         f"    public const val FIRMWARE_VERSION: String = \"{'.'.join(map(str, model.fw_version))}\"",
         f"    public const val MAX_PAYLOAD: Int = {model.max_payload}",
         f"    public const val SETTINGS_SIZE: Int = {model.settings.size}",
         f"    public const val STATE_SIZE: Int = {model.state.size}",
         "}", ""]
    for name, e in model.enums.items():
        o += kt_enum(name, e) + [""]
    for name, fl in model.flags.items():
        o += kt_flags(name, fl) + [""]
    o += ["/** A packet of the protocol: its type and payload codec. */",
          "public sealed interface Packet {",
          "    /** The packet type (frame header byte 0). */",
          "    public val type: Int",
          "    /** The payload bytes, little-endian and packed. */",
          "    public fun encodePayload(): ByteArray", "}", ""]
    for s in model.structs.values():
        o += [kt_class(model, s), ""]
    o += [kt_class(model, model.settings), ""]
    for p in model.packets:
        o += [kt_class(model, p, packet=True), ""]
    o += ["/** Size limits and direction of every packet type, from the schema. */",
          "public class PacketSpec(",
          "    public val type: Int, public val name: String, public val minSize: Int, public val maxSize: Int,",
          "    public val fromRobot: Boolean, public val acked: Boolean,",
          "    /** A read: the robot answers it every time and never takes it for a retransmission. */",
          "    public val idempotent: Boolean,",
          "    /** Obeyed from a host that only watches the robot (reads, heartbeats, the role, goodbye, stop). */",
          "    public val watcherOk: Boolean,",
          ")", "",
          "/** Every packet type of the protocol. */",
          "public val PACKET_SPECS: Map<Int, PacketSpec> = listOf("]
    for p in model.packets:
        o.append(f"    PacketSpec({p.id}, \"{p.name}\", {p.min_size}, {p.max_size}, {str(p.dir == 'r2h').lower()}, "
                 f"{str(p.ack).lower()}, {str(p.idempotent).lower()}, {str(p.watcher_ok).lower()}),")
    o += [").associateBy { it.type }", "",
          "/** [PACKET_SPECS] indexed by type (0..255): one array load per frame. */",
          "internal val PACKET_SPEC_BY_TYPE: Array<PacketSpec?> = arrayOfNulls<PacketSpec>(256).also { a -> PACKET_SPECS.values.forEach { a[it.type] = it } }", "",
          "/** Decodes the payload in [b] from [at] to [end], whose length was already checked against [PACKET_SPECS]. */",
          "internal fun decodePacketPayload(type: Int, b: ByteArray, at: Int, end: Int): Packet = when (type) {"]
    for p in model.packets:
        o.append(f"    {p.id} -> {p.kt_name}.decode(b, at, end)")
    o += ["    else -> throw IllegalArgumentException(\"unknown packet type $type\")", "}", "",
          "/** The encoded payload size of [p] in bytes. */",
          "internal fun payloadSizeOf(p: Packet): Int = when (p) {"]
    for p in model.packets:
        o.append(f"    is {p.kt_name} -> p.payloadSize")
    o += ["}", "", "/** Writes the payload of [p] into [b] from [at] ([payloadSizeOf] bytes): no intermediate array. */",
          "internal fun encodePayloadInto(p: Packet, b: ByteArray, at: Int): Unit = when (p) {"]
    for p in model.packets:
        o.append(f"    is {p.kt_name} -> p.encodeTo(b, at)")
    o += ["}", ""]
    # settings field table
    o += ["/** The wire type of a settings leaf. */",
          "public enum class FieldType(public val size: Int) { U8(1), I8(1), U16(2), I16(2), U32(4), I32(4), F32(4), CHAR(1) }", "",
          "/**",
          " * One leaf of [Settings]: its dotted path, place in the struct and the range the robot enforces.",
          " * `count` > 1 for arrays (and the length of a CHAR text).",
          " */",
          "public class SettingsFieldInfo(",
          "    public val path: String, public val offset: Int, public val type: FieldType, public val count: Int,",
          "    public val min: Double?, public val max: Double?, public val unit: String, public val doc: String,",
          ") {",
          "    /** Size in bytes. */",
          "    public val size: Int get() = type.size * count",
          "    override fun toString(): String = \"$path@$offset:$type[$count]\"",
          "}", "",
          "/** Every leaf of [Settings], in struct order. */",
          "public val SETTINGS_FIELDS: List<SettingsFieldInfo> = listOf("]
    for path, f, off, _ in model.settings_leaves():
        t = "CHAR" if f.is_char else f.base.upper()
        mn = "null" if f.min is None else repr(float(f.min))
        mx = "null" if f.max is None else repr(float(f.max))
        o.append(f"    SettingsFieldInfo(\"{path}\", {off}, FieldType.{t}, {f.count or 1}, {mn}, {mx}, "
                 f"{json.dumps(f.unit)}, {json.dumps(f.doc)}),")
    o += [")", ""]
    # defaults
    vals = {}
    for g in model.settings_groups:
        gv = {}
        for f in g.struct.fields:
            d = g.defaults.get(f.name, f.default)
            gv[f.name] = [d] * f.count if f.count and not f.is_char else d
            if f.base == "f32":
                gv[f.name] = [float(x) for x in gv[f.name]] if isinstance(gv[f.name], list) else float(gv[f.name])
        vals[g.name] = gv
    o += ["/** The settings compiled into the firmware. */",
          f"public val SETTINGS_DEFAULTS: Settings = {kt_construct(model, model.settings, vals)}", ""]
    return "\n".join(o)




def emit(model):
    return {OUT: codecs(model)}
