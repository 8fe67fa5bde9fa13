"""sdk/protocol's GoldenVectorsTest.kt: every golden frame decodes to the schema's values and re-encodes
to the same bytes."""
from .kotlin_codecs import kt_construct
from .model import HEADER, camel

OUT = "sdk/protocol/src/commonTest/kotlin/org/pocketbot/protocol/GoldenVectorsTest.kt"

def emit(model, vectors):
    by_name = {p.name: p for p in model.packets}
    o = [f"// {HEADER}", "package org.pocketbot.protocol", "",
         "import kotlin.test.Test", "import kotlin.test.assertContentEquals", "import kotlin.test.assertEquals", "",
         "/** The golden vectors of protocol/golden/vectors.json: decode to the schema's values, re-encode to the same bytes. */",
         "class GoldenVectorsTest {",
         "    private fun hex(s: String): ByteArray = ByteArray(s.length / 2) { s.substring(2 * it, 2 * it + 2).toInt(16).toByte() }",
         "",
         "    private fun check(expected: Packet, seq: Int, frameHex: String, slipHex: String) {",
         "        val frame = hex(frameHex)",
         "        val decoded = Frames.decode(frame)",
         "        assertEquals(FrameResult.Decoded(seq, expected), decoded, \"decoding ${expected::class.simpleName}\")",
         "        assertContentEquals(frame, Frames.encode(expected, seq), \"encoding ${expected::class.simpleName}\")",
         "        assertContentEquals(hex(slipHex), Slip.encode(frame), \"SLIP of ${expected::class.simpleName}\")",
         "    }", ""]
    for v in vectors:
        p = by_name[v["packet"]]
        o.append(f"    @Test fun {camel(v['name'])}() = check({kt_construct(model, p, v['values'])}, {v['seq']},")
        o.append(f"        \"{v['frame']}\",")
        o.append(f"        \"{v['slip']}\")")
        o.append("")
    o += ["}", ""]
    return {OUT: "\n".join(o)}
