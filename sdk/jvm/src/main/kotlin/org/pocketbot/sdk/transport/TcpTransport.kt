package org.pocketbot.sdk.transport

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.TimeoutCancellationException
import kotlinx.coroutines.withTimeout
import org.pocketbot.sdk.transport.internal.SocketLoop
import java.net.InetSocketAddress
import java.net.StandardSocketOptions
import java.nio.ByteBuffer
import java.nio.channels.SelectionKey
import java.nio.channels.SocketChannel
import kotlin.coroutines.CoroutineContext
import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds

/**
 * A [Transport] over TCP: SLIP frames on a socket, as the emulator's robot endpoints and any robot bridged to
 * TCP (a serial-to-TCP server, `socat`, an ESP32 bridge) speak. Non-blocking NIO sockets share a few event-loop
 * threads, and by default each socket is read and its frames decoded right on its loop; a robot
 * connected through a [TcpRobotDevice] runs its link on that loop too, so a frame reaches the robot's state without
 * a thread hand-over. The socket has `TCP_NODELAY` set, so a frame leaves as soon as it is sent.
 *
 * Everything else (framing errors, lost link, [close]) is [SlipStreamTransport]'s behaviour. Safe to use from any
 * thread and coroutine.
 *
 * ```
 * val transport = TcpTransport.open("127.0.0.1", 40001)
 * transport.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, session), seq = 0))
 * println(Frames.decode(transport.incoming.receive()))
 * transport.close()
 * ```
 */
public class TcpTransport private constructor(
    address: String,
    stream: ByteStream,
    context: CoroutineContext,
) : SlipStreamTransport(address, stream, context) {
    public companion object {
        /** How long [open] waits by default for the robot to accept the connection. */
        public val DEFAULT_CONNECT_TIMEOUT: Duration = 5.seconds

        /**
         * Connects to a robot at [host]:[port] and returns the open transport; suspends until connected.
         * Throws [TransportLostException] when nothing accepts the connection within [timeout].
         *
         * @param context where the transport's reader runs; its [kotlinx.coroutines.Job], if any, becomes the
         *   parent of the reader.
         */
        public suspend fun open(
            host: String,
            port: Int,
            timeout: Duration = DEFAULT_CONNECT_TIMEOUT,
            context: CoroutineContext = Dispatchers.Unconfined,
        ): TcpTransport = connect(host, port, timeout, context, SocketLoop.next())

        /** The old name of [open]. */
        @Deprecated("open, the verb SerialTransport.open and RobotDevice.open use", ReplaceWith("open(host, port, timeout, context)"))
        public suspend fun connect(
            host: String,
            port: Int,
            timeout: Duration = DEFAULT_CONNECT_TIMEOUT,
            context: CoroutineContext = Dispatchers.Unconfined,
        ): TcpTransport = open(host, port, timeout, context)

        /** [open] with its socket served by [loop]. */
        internal suspend fun connect(
            host: String,
            port: Int,
            timeout: Duration,
            context: CoroutineContext = Dispatchers.Unconfined,
            loop: SocketLoop,
        ): TcpTransport = TcpTransport(tcpAddress(host, port), openSocket(host, port, timeout, loop), context)

        /**
         * A connected non-blocking socket to [host]:[port] as a [ByteStream] served by [loop]; throws
         * [TransportLostException] when nothing accepts the connection within [timeout].
         */
        internal suspend fun openSocket(host: String, port: Int, timeout: Duration, loop: SocketLoop): ByteStream {
            require(port in 1..65535) { "port $port is not a TCP port" }
            val address = tcpAddress(host, port)
            val channel = SocketChannel.open()
            try {
                channel.configureBlocking(false)
                channel.setOption(StandardSocketOptions.TCP_NODELAY, true)
                channel.setOption(StandardSocketOptions.SO_KEEPALIVE, true)
                withTimeout(timeout) {
                    if (!channel.connect(InetSocketAddress(host, port))) {
                        while (!channel.finishConnect()) loop.await(channel, SelectionKey.OP_CONNECT)
                    }
                }
            } catch (e: TimeoutCancellationException) {
                channel.close()
                throw TransportLostException("$address: no connection within $timeout", e)
            } catch (e: CancellationException) {
                channel.close()
                throw e
            } catch (e: java.net.ConnectException) {
                channel.close()
                throw TransportLostException("$address: nothing listens there (connection refused): $NOT_LISTENING", e)
            } catch (e: Exception) {
                channel.close()
                throw TransportLostException("$address: ${e.message?.lowercase() ?: e::class.simpleName}", e)
            }
            return SocketStream(channel, loop)
        }

        /** What a refused connection most likely means. */
        internal const val NOT_LISTENING = "is the emulator (make emulator, pocketbot emulator) or the robot's TCP bridge running?"

        internal fun tcpAddress(host: String, port: Int): String =
            if (':' in host) "tcp://[$host]:$port" else "tcp://$host:$port"
    }
}

/** A non-blocking socket as a [ByteStream]: reads and writes that would block wait on its [loop]. */
private class SocketStream(private val channel: SocketChannel, private val loop: SocketLoop) : ByteStream {
    /** The last read left room in the buffer: the socket is most likely empty, so wait before reading again. */
    private var drained = false

    override suspend fun read(buffer: ByteArray, offset: Int, length: Int): Int {
        val into = ByteBuffer.wrap(buffer, offset, length)
        // Waiting first after a short read saves the read that would only say "nothing yet" (one system call per
        // frame at a robot's pace); readiness is level-triggered, so waiting on data already there returns at once.
        if (drained) loop.await(channel, SelectionKey.OP_READ)
        while (true) {
            val n = channel.read(into)
            if (n != 0) {
                drained = n in 1 until length
                return n
            }
            loop.await(channel, SelectionKey.OP_READ)
        }
    }

    override suspend fun write(bytes: ByteArray) {
        val from = ByteBuffer.wrap(bytes)
        while (from.hasRemaining()) {
            if (channel.write(from) == 0) loop.await(channel, SelectionKey.OP_WRITE)
        }
    }

    override fun close() {
        channel.close()
    }
}
