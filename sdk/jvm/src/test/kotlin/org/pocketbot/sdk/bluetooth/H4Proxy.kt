package org.pocketbot.sdk.bluetooth

import java.io.ByteArrayOutputStream
import java.io.IOException
import java.io.InputStream
import java.io.OutputStream
import java.net.InetAddress
import java.net.InetSocketAddress
import java.net.ServerSocket
import java.net.Socket
import java.util.concurrent.atomic.AtomicInteger
import java.util.concurrent.atomic.AtomicReference

/**
 * An H4 wire between a robot and its controller, with faults a real one may have, in the direction towards the robot:
 * ACL data cut into fragments of [fragment] bytes (a real controller may deliver an L2CAP PDU in several ACL packets;
 * Bumble's never does), and, on request, a garbage burst or a lost byte. The robot connects to [endpoint]; each
 * connection gets its own connection to [controller]. Robot-to-controller bytes pass unchanged.
 */
class H4Proxy(private val controller: InetSocketAddress, private val fragment: Int = Int.MAX_VALUE) : AutoCloseable {
    private val server = ServerSocket(0, 4, InetAddress.getLoopbackAddress())
    val endpoint = InetSocketAddress(InetAddress.getLoopbackAddress(), server.localPort)
    private val garbage = AtomicReference<ByteArray?>(null)
    private val dropsPending = AtomicInteger()
    private val sockets = java.util.concurrent.CopyOnWriteArrayList<Socket>()

    /** ACL packets towards the robot that were cut into fragments, and fragments sent, so far. */
    val aclPacketsCut = AtomicInteger()
    val fragmentsSent = AtomicInteger()

    init {
        Thread({ accept() }, "h4-proxy").apply { isDaemon = true; start() }
    }

    /** Puts [bytes] on the wire towards the robot between two packets. */
    fun injectGarbage(bytes: ByteArray) { garbage.set(bytes) }

    /** Loses one byte in the middle of the next ACL packet towards the robot. */
    fun dropAByte() { dropsPending.incrementAndGet() }

    private fun accept() {
        while (!server.isClosed) {
            val robot = try { server.accept() } catch (_: IOException) { return }
            val upstream = try { Socket().apply { tcpNoDelay = true; connect(controller, 2000) } } catch (_: IOException) { robot.close(); continue }
            robot.tcpNoDelay = true
            sockets += robot; sockets += upstream
            pump("h4-proxy-up") { robot.getInputStream().copyTo(upstream.getOutputStream(), 512) }.also { it.onEnd { upstream.close(); robot.close() } }
            pump("h4-proxy-down") { towardsRobot(upstream.getInputStream(), robot.getOutputStream()) }.also { it.onEnd { upstream.close(); robot.close() } }
        }
    }

    private class Pump(val thread: Thread) { var end: () -> Unit = {}; fun onEnd(f: () -> Unit) { end = f } }

    private fun pump(name: String, body: () -> Unit): Pump {
        lateinit var p: Pump
        p = Pump(Thread({ try { body() } catch (_: IOException) { } finally { p.end() } }, name).apply { isDaemon = true })
        p.thread.start()
        return p
    }

    /** Reads whole H4 packets from the controller and writes them to the robot, cut and spoiled as asked. */
    private fun towardsRobot(input: InputStream, output: OutputStream) {
        while (true) {
            val type = input.read()
            if (type < 0) return
            garbage.getAndSet(null)?.let { output.write(it) }
            when (type) {
                EVENT -> {
                    val header = input.readNBytes(2)
                    val body = input.readNBytes(header[1].toInt() and 0xFF)
                    output.write(byteArrayOf(EVENT.toByte()) + header + body)
                }
                ACL -> {
                    val header = input.readNBytes(4)
                    val handleAndFlags = (header[0].toInt() and 0xFF) or ((header[1].toInt() and 0xFF) shl 8)
                    val body = input.readNBytes((header[2].toInt() and 0xFF) or ((header[3].toInt() and 0xFF) shl 8))
                    output.write(acl(handleAndFlags, body))
                }
                else -> { output.write(type); output.write(input.readNBytes(input.available())) }
            }
            output.flush()
        }
    }

    private fun acl(handleAndFlags: Int, body: ByteArray): ByteArray {
        val out = ByteArrayOutputStream()
        val pieces = body.toList().chunked(fragment).map { it.toByteArray() }.ifEmpty { listOf(ByteArray(0)) }
        if (pieces.size > 1) aclPacketsCut.incrementAndGet()
        for ((k, piece) in pieces.withIndex()) {
            // Packet boundary flag: the first fragment keeps the controller's, the others continue it (0b01).
            val flags = if (k == 0) handleAndFlags else (handleAndFlags and 0x0FFF) or (CONTINUING shl 12)
            out.write(byteArrayOf(ACL.toByte(), flags.toByte(), (flags shr 8).toByte(), piece.size.toByte(), (piece.size shr 8).toByte()))
            out.write(piece)
            fragmentsSent.incrementAndGet()
        }
        val bytes = out.toByteArray()
        if (dropsPending.get() > 0 && bytes.size > 8) {
            dropsPending.decrementAndGet()
            val at = bytes.size / 2
            return bytes.copyOfRange(0, at) + bytes.copyOfRange(at + 1, bytes.size)
        }
        return bytes
    }

    override fun close() {
        server.close()
        for (s in sockets) runCatching { s.close() }
    }

    private companion object {
        const val ACL = 0x02
        const val EVENT = 0x04
        const val CONTINUING = 0b01
    }
}
