package org.pocketbot.sdk.transport

import io.ktor.network.selector.SelectorManager
import io.ktor.network.sockets.Socket
import io.ktor.network.sockets.aSocket
import io.ktor.network.sockets.openReadChannel
import io.ktor.network.sockets.openWriteChannel
import io.ktor.utils.io.ByteReadChannel
import io.ktor.utils.io.ByteWriteChannel
import io.ktor.utils.io.readAvailable
import io.ktor.utils.io.writeFully
import kotlin.coroutines.CoroutineContext
import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds
import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.TimeoutCancellationException
import kotlinx.coroutines.withTimeout

/**
 * A [Transport] over TCP: SLIP frames on a socket, as the emulator's robot endpoints and any robot bridged to
 * TCP (a serial-to-TCP server, `socat`, an ESP32 bridge) speak. Built on ktor-network's non-blocking sockets;
 * the socket has `TCP_NODELAY` set, so a frame leaves as soon as it is sent.
 *
 * Everything else (framing errors, lost link, [close]) is [SlipStreamTransport]'s behaviour. Safe to use from any
 * thread and coroutine.
 *
 * ```
 * val transport = TcpTransport.connect("127.0.0.1", 40001)
 * transport.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION), seq = 0))
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
        /** How long [connect] waits by default for the robot to accept the connection. */
        public val DEFAULT_CONNECT_TIMEOUT: Duration = 5.seconds

        /**
         * Connects to a robot at [host]:[port] and returns the open transport; suspends until connected.
         * Throws [TransportLostException] when nothing accepts the connection within [timeout].
         *
         * @param context where the transport's reader runs; its [kotlinx.coroutines.Job], if any, becomes the
         *   parent of the reader.
         */
        public suspend fun connect(
            host: String,
            port: Int,
            timeout: Duration = DEFAULT_CONNECT_TIMEOUT,
            context: CoroutineContext = Dispatchers.IO,
        ): TcpTransport {
            require(port in 1..65535) { "port $port is not a TCP port" }
            val address = tcpAddress(host, port)
            val socket = try {
                withTimeout(timeout) {
                    aSocket(selector).tcp().connect(host, port) {
                        noDelay = true
                        keepAlive = true
                    }
                }
            } catch (e: TimeoutCancellationException) {
                throw TransportLostException("$address: no connection within $timeout", e)
            } catch (e: CancellationException) {
                throw e
            } catch (e: Exception) {
                throw TransportLostException("$address: cannot connect: ${e.message ?: e::class.simpleName}", e)
            }
            return TcpTransport(address, SocketStream(socket), context)
        }

        /** One selector for every TCP transport of the process: its coroutine runs on [Dispatchers.IO]. */
        private val selector: SelectorManager by lazy { SelectorManager(Dispatchers.IO) }

        internal fun tcpAddress(host: String, port: Int): String =
            if (':' in host) "tcp://[$host]:$port" else "tcp://$host:$port"
    }
}

/** A ktor socket as a [ByteStream]. */
private class SocketStream(private val socket: Socket) : ByteStream {
    private val input: ByteReadChannel = socket.openReadChannel()
    private val output: ByteWriteChannel = socket.openWriteChannel(autoFlush = false)

    override suspend fun read(buffer: ByteArray, offset: Int, length: Int): Int {
        val n = input.readAvailable(buffer, offset, length)
        return if (n == 0 && input.isClosedForRead) -1 else n
    }

    override suspend fun write(bytes: ByteArray) {
        output.writeFully(bytes)
        output.flush()
    }

    override fun close() {
        socket.close()
    }
}
