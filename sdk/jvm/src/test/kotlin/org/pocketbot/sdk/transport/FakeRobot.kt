package org.pocketbot.sdk.transport

import java.io.InputStream
import java.io.OutputStream
import java.util.concurrent.LinkedBlockingQueue
import java.util.concurrent.TimeUnit
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder

/**
 * The robot end of a byte link for tests: reads SLIP frames on its own thread, answers a [HelloRequest] with a
 * [Hello] (same seq) and keeps every other frame in [received]. With [answersCommands] it also acknowledges every
 * acknowledged command and answers `set_role` (this host drives), `read_settings` (the default settings) and
 * `read_movements` (an empty log), enough for the SDK's handshake. Works over any pair of blocking streams: a socket, a pty.
 */
class FakeRobot(
    private val input: InputStream,
    private val output: OutputStream,
    val hello: Hello = hello(3, "PocketBot-3"),
    private val onEnd: () -> Unit = {},
    private val answersCommands: Boolean = false,
) : AutoCloseable {
    val received = LinkedBlockingQueue<ByteArray>()
    @Volatile var ended = false
        private set
    private val thread = Thread(::run, "fake-robot").apply { isDaemon = true; start() }

    private fun run() {
        val decoder = SlipDecoder()
        val buf = ByteArray(512)
        try {
            while (true) {
                val n = input.read(buf)
                if (n < 0) break
                decoder.feed(buf, 0, n) { frame ->
                    val r = Frames.decode(frame)
                    if (r is FrameResult.Decoded && r.packet is HelloRequest) sendFrame(Frames.encode(hello, r.seq))
                    else {
                        received.add(frame)
                        if (answersCommands && r is FrameResult.Decoded) answer(r.seq, r.packet)
                    }
                }
            }
        } catch (_: Exception) {
            // the link went away: that is how tests end it
        } finally {
            ended = true
            onEnd()
        }
    }

    private fun answer(seq: Int, packet: org.pocketbot.protocol.Packet) {
        if (org.pocketbot.protocol.PACKET_SPECS[packet.type]?.acked != true) return
        when (packet) {
            is org.pocketbot.protocol.ReadSettings -> DEFAULT_SETTINGS.toList().chunked(64).forEachIndexed { i, chunk ->
                sendFrame(Frames.encode(org.pocketbot.protocol.SettingsData(i * 64, chunk.toByteArray()), 0))
            }
            is org.pocketbot.protocol.ReadMovements ->
                sendFrame(Frames.encode(org.pocketbot.protocol.MovementLog(0, 0, 0, List(16) { 0 }, List(16) { 0 }, List(16) { 0f }), 0))
            // A robot no other host drives: this one drives when it asks to.
            is org.pocketbot.protocol.SetRole ->
                sendFrame(Frames.encode(org.pocketbot.protocol.Driver(if (packet.role == 0) 0 else 1, 1, packet.label, 0), 0))
            else -> {}
        }
        sendFrame(Frames.encode(org.pocketbot.protocol.Ack(packet.type), seq))
    }

    fun sendFrame(frame: ByteArray) = sendRaw(Slip.encode(frame))

    @Synchronized
    fun sendRaw(bytes: ByteArray) {
        output.write(bytes)
        output.flush()
    }

    fun nextFrame(seconds: Long = 5): ByteArray =
        received.poll(seconds, TimeUnit.SECONDS) ?: error("the fake robot received no frame within $seconds s")

    fun awaitEnd(seconds: Long = 5) {
        thread.join(seconds * 1000)
        check(ended) { "the fake robot's link did not end within $seconds s" }
    }

    override fun close() {
        runCatching { input.close() }
        runCatching { output.close() }
        onEnd()
    }

    companion object {
        val DEFAULT_SETTINGS: ByteArray = ByteArray(ProtocolInfo.SETTINGS_SIZE).also { org.pocketbot.protocol.SETTINGS_DEFAULTS.encodeTo(it, 0) }

        fun hello(id: Int, name: String) = Hello(id, name, 0, 1, 0, ProtocolInfo.VERSION, ProtocolInfo.LAYOUT_HASH,
            ProtocolInfo.SETTINGS_SIZE, ProtocolInfo.STATE_SIZE, 0, org.pocketbot.protocol.Crc16.compute(DEFAULT_SETTINGS))
    }
}
