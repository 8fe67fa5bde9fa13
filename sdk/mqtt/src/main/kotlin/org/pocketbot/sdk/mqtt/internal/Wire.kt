package org.pocketbot.sdk.mqtt.internal

import org.pocketbot.protocol.Frames

/**
 * The payloads of the `down`, `watch` and `up` topics (docs/fleet.md): `u8 version, u8 kind, u64 big-endian send
 * time in ms on the sender's monotonic clock`, then for frames each frame after its u16 big-endian length (header,
 * payload, CRC, no SLIP), for open the client's MQTT client id, for closed the reason, both UTF-8.
 */
internal object Wire {
    const val VERSION = 1
    const val FRAMES = 0
    const val OPEN = 1
    const val CLOSE = 2
    const val CLOSED = 3
    const val HEADER_SIZE = 10

    /** The largest down message a gateway reads. */
    const val MAX_DOWN_MESSAGE = 16 * 1024

    fun frames(timeMs: Long, frames: List<ByteArray>): ByteArray {
        val out = ByteArray(HEADER_SIZE + frames.sumOf { 2 + it.size })
        header(out, FRAMES, timeMs)
        var at = HEADER_SIZE
        for (f in frames) {
            out[at] = (f.size shr 8).toByte()
            out[at + 1] = f.size.toByte()
            f.copyInto(out, at + 2)
            at += 2 + f.size
        }
        return out
    }

    fun text(kind: Int, timeMs: Long, text: String): ByteArray {
        val bytes = text.encodeToByteArray()
        return ByteArray(HEADER_SIZE + bytes.size).also { header(it, kind, timeMs); bytes.copyInto(it, HEADER_SIZE) }
    }

    private fun header(out: ByteArray, kind: Int, timeMs: Long) {
        out[0] = VERSION.toByte()
        out[1] = kind.toByte()
        for (i in 0 until 8) out[2 + i] = (timeMs ushr (56 - 8 * i)).toByte()
    }

    /** What [decode] made of a message. */
    sealed interface Decoded
    class Message(val kind: Int, val timeMs: Long, val frames: List<ByteArray>, val text: String?) : Decoded
    object Garbage : Decoded
    object Oversize : Decoded

    /** Reads a message of one of [kinds]; never throws. */
    fun decode(bytes: ByteArray, kinds: Set<Int>): Decoded {
        if (bytes.size < HEADER_SIZE || bytes[0].toInt() != VERSION) return Garbage
        val kind = bytes[1].toInt() and 0xFF
        if (kind !in kinds) return Garbage
        var time = 0L
        for (i in 0 until 8) time = (time shl 8) or (bytes[2 + i].toLong() and 0xFF)
        if (kind != FRAMES) {
            val text = bytes.decodeToString(HEADER_SIZE, bytes.size, throwOnInvalidSequence = false)
            return Message(kind, time, emptyList(), text)
        }
        val frames = ArrayList<ByteArray>()
        var at = HEADER_SIZE
        while (at < bytes.size) {
            if (at + 2 > bytes.size) return Garbage
            val size = ((bytes[at].toInt() and 0xFF) shl 8) or (bytes[at + 1].toInt() and 0xFF)
            if (size > Frames.MAX_FRAME) return Oversize
            if (size < Frames.HEADER_SIZE + Frames.CRC_SIZE || at + 2 + size > bytes.size) return Garbage
            frames += bytes.copyOfRange(at + 2, at + 2 + size)
            at += 2 + size
        }
        return Message(kind, time, frames, null)
    }
}

/** The topics under `pb/v1` (docs/fleet.md). Ids are topic-safe: no `/`, `+`, `#`. */
internal object Topics {
    const val PREFIX = "pb/v1"
    const val CLIENTS = "clients"

    fun status(gateway: String) = "$PREFIX/$gateway/status"
    fun info(gateway: String, robot: String) = "$PREFIX/$gateway/$robot/info"
    fun lease(gateway: String, robot: String) = "$PREFIX/$gateway/$robot/lease"
    fun session(gateway: String, robot: String, kind: String, user: String, session: String) =
        "$PREFIX/$gateway/$robot/$kind/$user/$session"
    fun client(user: String, clientId: String) = "$PREFIX/$CLIENTS/$user/$clientId"

    const val DOWN = "down"
    const val WATCH = "watch"
    const val UP = "up"

    /** A topic's levels after `pb/v1`, or null when it is not under it. */
    fun levels(topic: String): List<String>? =
        if (topic.startsWith("$PREFIX/")) topic.substring(PREFIX.length + 1).split('/') else null

    private val UNSAFE = Regex("[^A-Za-z0-9._-]")

    /** [name] as a topic level: anything but letters, digits, `.`, `_` and `-` becomes `_`. */
    fun safe(name: String): String = name.replace(UNSAFE, "_").ifEmpty { "_" }

    fun isSafe(id: String): Boolean = id.isNotEmpty() && !UNSAFE.containsMatchIn(id)
}

/** Milliseconds on this host's monotonic clock: the send and receive times of the age check. */
internal fun monotonicMs(): Long = System.nanoTime() / 1_000_000
