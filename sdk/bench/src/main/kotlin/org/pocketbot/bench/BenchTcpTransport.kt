package org.pocketbot.bench

import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.channels.ReceiveChannel
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport
import org.pocketbot.sdk.transport.TransportLostException
import java.net.InetSocketAddress
import java.net.Socket
import java.util.concurrent.ConcurrentHashMap

/**
 * A plain TCP + SLIP transport to an emulator endpoint that notes, for every state frame, the moment its last byte
 * was decoded (System.nanoTime), keyed by the robot time in the frame. Only for measuring the SDK's host-side path.
 */
class BenchTcpTransport(private val port: Int, val arrivals: ConcurrentHashMap<Long, Long>) : Transport {
    private val socket = Socket().also { it.tcpNoDelay = true; it.connect(InetSocketAddress("127.0.0.1", this.port), 2000) }
    private val frames = Channel<ByteArray>(Channel.UNLIMITED)
    private val out = socket.getOutputStream()
    @Volatile var slipBytes = 0L
    override val address: String = "bench-tcp://127.0.0.1:$port"
    override val incoming: ReceiveChannel<ByteArray> get() = frames

    private val reader = Thread({
        val decoder = SlipDecoder()
        val buf = ByteArray(4096)
        try {
            val input = socket.getInputStream()
            while (true) {
                val n = input.read(buf)
                if (n < 0) break
                slipBytes += n
                decoder.feed(buf, 0, n) { frame ->
                    val now = System.nanoTime()
                    val type = frame[0].toInt()
                    if ((type == 2 || type == 3) && frame.size >= 7) {
                        val t = (frame[3].toLong() and 0xFF) or ((frame[4].toLong() and 0xFF) shl 8) or
                            ((frame[5].toLong() and 0xFF) shl 16) or ((frame[6].toLong() and 0xFF) shl 24)
                        arrivals[t] = now
                    }
                    frames.trySend(frame)
                }
            }
            frames.close(TransportLostException("$address: closed by the robot"))
        } catch (e: Exception) {
            frames.close(TransportLostException("$address: ${e.message}", e))
        }
    }, "bench-tcp-$port").apply { isDaemon = true; start() }

    override suspend fun send(frame: ByteArray) {
        try {
            synchronized(out) { out.write(Slip.encode(frame)); out.flush() }
        } catch (e: Exception) {
            throw TransportLostException("$address: ${e.message}", e)
        }
    }

    override fun close() {
        socket.close()
        frames.close()
    }
}

class BenchTcpDevice(override val name: String, private val port: Int) : RobotDevice {
    val arrivals = ConcurrentHashMap<Long, Long>()
    var transport: BenchTcpTransport? = null
    override val address: String get() = "bench-tcp://127.0.0.1:$port"
    override suspend fun open(): Transport = BenchTcpTransport(port, arrivals).also { transport = it }
}
