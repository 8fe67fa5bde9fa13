package org.pocketbot.protocol

import com.code_intelligence.jazzer.junit.FuzzTest

/**
 * Jazzer fuzz tests of the Kotlin decoders: whatever bytes arrive, [Frames.decode] returns a result and never
 * throws, and [SlipDecoder] never throws and never emits a frame longer than its limit.
 *
 * In a plain `mvn verify` Jazzer runs both methods in regression mode: once per seed in
 * `src/test/resources/org/pocketbot/protocol/FuzzTestInputs/<method>/` (the golden vectors SLIP-encoded, and
 * broken streams). With `JAZZER_FUZZ=1` it fuzzes one method, guided by coverage, for its `maxDuration`:
 * sdk/jvm's pom runs [decodersNeverThrowBriefly] that way in `verify` (execution `fuzz-smoke`, 10 s) and
 * [decodersNeverThrow] in the `fuzz` profile (`make fuzz`, 5 min). A failing input is written next to the seeds'
 * folder under target/jazzer (see the pom); copy it into the seeds to keep it as a regression test.
 *
 * Input layout: byte 0 = the SLIP decoder's frame limit - 1, byte 1 = the read chunk size - 1 (so the fuzzer
 * explores limits and chunking), the rest = the byte stream.
 */
class FuzzTest {
    @FuzzTest(maxDuration = "5m")
    fun decodersNeverThrow(input: ByteArray) = checkDecoders(input)

    @FuzzTest(maxDuration = "10s")
    fun decodersNeverThrowBriefly(input: ByteArray) = checkDecoders(input)

    private fun checkDecoders(input: ByteArray) {
        Frames.decode(input)
        if (input.size < 2) return
        val maxFrame = 1 + (input[0].toInt() and 0xFF)
        val chunk = 1 + (input[1].toInt() and 0x3F)
        val stream = input.copyOfRange(2, input.size)
        Frames.decode(stream)

        // the stream cut into chunks: frames within the limit, each one decodable without an exception
        val decoder = SlipDecoder(maxFrame)
        var offset = 0
        while (offset < stream.size) {
            val n = minOf(chunk, stream.size - offset)
            decoder.feed(stream, offset, n, onError = { }) { frame ->
                check(frame.size in 1..maxFrame) { "SlipDecoder($maxFrame) emitted a frame of ${frame.size} bytes" }
                Frames.decode(frame)
            }
            offset += n
        }

        // SLIP round trip: any non-empty frame within the limit comes back unchanged, alone
        if (stream.isNotEmpty()) {
            val frames = mutableListOf<ByteArray>()
            SlipDecoder(stream.size).feed(Slip.encode(stream), onError = { error("round trip: $it") }) { frames += it }
            check(frames.size == 1 && frames[0].contentEquals(stream)) { "SLIP round trip changed the frame" }
        }
    }
}
