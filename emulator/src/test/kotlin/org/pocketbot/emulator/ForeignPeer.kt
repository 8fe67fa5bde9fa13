package org.pocketbot.emulator

import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder
import java.net.InetAddress
import java.net.ServerSocket
import java.net.Socket
import java.util.concurrent.CopyOnWriteArrayList

/**
 * Something on a TCP port of this machine that a robot's address can name, but that is no robot of this protocol:
 * with [answer] it says hello as robot [NAME] whose firmware speaks [protocolVersion] with [layoutHash], then nothing;
 * without, it accepts the connection and never says a word. The faces' tests (CLI, panel) use it for the robots a
 * user meets with other firmware, or for a port that is not a robot at all; it ships in the emulator's test jar.
 */
class ForeignPeer(
    private val answer: Boolean = true,
    private val protocolVersion: Int = ProtocolInfo.VERSION,
    private val layoutHash: Long = ProtocolInfo.LAYOUT_HASH,
) : AutoCloseable {
    private val server = ServerSocket(0, 8, InetAddress.getLoopbackAddress())
    private val connections = CopyOnWriteArrayList<Socket>()

    val port: Int = server.localPort

    /** Where it listens, as a robot address. */
    val address: String = "tcp://127.0.0.1:$port"

    init {
        Thread {
            while (!server.isClosed) {
                val socket = try { server.accept() } catch (_: Exception) { break }
                connections += socket
                Thread { serve(socket) }.apply { isDaemon = true; start() }
            }
        }.apply { isDaemon = true; start() }
    }

    private fun serve(socket: Socket) {
        val decoder = SlipDecoder()
        val buf = ByteArray(512)
        try {
            val input = socket.getInputStream()
            while (true) {
                val n = input.read(buf)
                if (n < 0) break
                decoder.feed(buf, 0, n) { frame ->
                    val decoded = Frames.decode(frame) as? FrameResult.Decoded ?: return@feed
                    if (answer && decoded.packet is HelloRequest) {
                        val hello = Hello(
                            robotId = 9, name = NAME, fwMajor = 0, fwMinor = 0, fwPatch = 1, protocolVersion = protocolVersion,
                            layoutHash = layoutHash, settingsSize = ProtocolInfo.SETTINGS_SIZE, stateSize = ProtocolInfo.STATE_SIZE,
                            sessionResumed = 0, settingsCrc = 0,
                        )
                        socket.getOutputStream().apply { write(Slip.encode(Frames.encode(hello, decoded.seq))); flush() }
                    }
                }
            }
        } catch (_: Exception) {
            // The client went away.
        }
    }

    override fun close() {
        server.close()
        connections.forEach { it.close() }
    }

    companion object {
        const val NAME = "Old-9"
    }
}
